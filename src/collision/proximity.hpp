#pragma once
// Closest points between surface primitives, for contact: a point and a triangle, or two
// segments. Both are "four corners y_0 .. y_3 and the vector between the closest points",
// r = sum_k w_k y_k, with the weights w from the closest points' barycentric coordinates.
//
// Why this form: the distance d = |r| is a minimum over those coordinates, and the constraint
// set (a triangle or a square of parameters) does not move with the corners, so by the envelope
// theorem its gradient is r/|r| times w per corner, with w held fixed: the same for every
// region the closest points lie in (vertex, edge, face), continuous across them, and needing no
// case-by-case formulas. The Hessian adds how the closest points slide (the free parameters, at
// most two): see distance_hessian.
//
// Floating point only: these measure distances for a penalty energy, they decide no topology.

#include <tetcut/types.hpp>

#include <Eigen/Core>

#include <array>

namespace tetcut::collision {

struct Proximity {
  Vec3 r = Vec3::Zero();      ///< first primitive's closest point minus the second's
  double distance = 0;        ///< |r|
  std::array<double, 4> w{};  ///< r = sum_k w[k] y[k]
  /// Closest-point parameters strictly inside their range (0, 1 or 2), and dw/du for each: how
  /// the closest points slide as the corners move (the Hessian's second term).
  int free = 0;
  std::array<std::array<double, 4>, 2> dw{};
};

/// Point y0 = p against triangle (y1, y2, y3) = (a, b, c): r = p - q, q the triangle's point
/// nearest p. A degenerate triangle (collinear corners) is treated as its longest edge's segment.
Proximity point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// Segment (y0, y1) = (a0, a1) against segment (y2, y3) = (b0, b1). Parallel segments have many
/// closest pairs; one is returned (the distance is the same).
Proximity segment_segment(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1);

using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

/// The gradient of the distance with respect to the 12 corner coordinates (corner k's at
/// 3k .. 3k + 2): w[k] r / |r|. Needs r != 0.
Vec12 distance_gradient(const Proximity& p);

/// The Hessian of the distance with respect to the 12 corner coordinates, where the closest
/// points are unique and r != 0: with D = d^2 = min_u |r(x, u)|^2,
///   D'' = 2 (w w^T) (x) I - 2 G (E^T E)^-1 G^T,
/// E = [dr/du_j] (3 x free), G's column j per corner k: dw_j[k] r + w[k] dr/du_j; then
/// d'' = D'' / (2d) - D' D'^T / (4 d^3). For tests and for exact Newton matrices; the
/// simulator uses the positive semi-definite part (see surface_contact.hpp).
Mat12 distance_hessian(const Proximity& p, const std::array<Vec3, 4>& y);

}  // namespace tetcut::collision
