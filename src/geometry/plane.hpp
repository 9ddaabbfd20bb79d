#pragma once
// Planes defined exactly by input doubles, and predicates on points defined as the meeting of three
// such planes (TPI points). Topology is decided by these predicates only; no coordinate of an
// implicit point is ever rounded while deciding.
//
// A plane is {x : n . x + d = 0}. Three definitions exist:
//   - through three input points p, q, r: n = (q - p) x (r - p), d = -n . p (degree 2 and 3);
//   - a wall through input points p, q and the coordinate axis e_k: n = (q - p) x e_k,
//     d = -n . p (degree 1 and 2). Within a cut triangle's plane, its walls are the lines of its
//     edges (the paper's virtual triangles);
//   - a world plane pulled back into the rest space of a tet whose corners moved (degree 5 and 6):
//     {X : world(phi(X)) = 0} for the affine map phi from the rest corners to the current corners.
//
// Every predicate is a filtered evaluation (geometry/approx.hpp) and, when that cannot decide, an
// exact one on each plane's exact form: integers proportional to (n, d) by a positive factor of
// the plane's own. Signs of the determinants below do not change under such factors.

#include <tetcut/types.hpp>

#include <gmpxx.h>

#include <array>
#include <cstdint>
#include <memory>

#include "geometry/approx.hpp"

namespace tetcut::geometry {

/// The plane's (n, d) times a positive factor, as integers.
using ExactPlane = std::array<mpz_class, 4>;

class Plane {
 public:
  enum class Kind : std::uint8_t { kThroughPoints, kWall, kPulledBack };

  Plane() = default;
  /// The plane through p, q, r, with normal (q - p) x (r - p). The points must not be collinear.
  static Plane through(const Vec3& p, const Vec3& q, const Vec3& r);
  /// The plane through p and q containing the direction of coordinate axis `axis`, with normal
  /// (q - p) x e_axis. q - p must not be parallel to that axis.
  static Plane wall(const Vec3& p, const Vec3& q, int axis);
  /// `world` pulled back into the rest space of a tet: {X : world(phi(X)) = 0}, phi the affine
  /// map taking rest[k] to current[k]; rest must be positively oriented. The function is
  /// Q(X) = -sum_k world(current[k]) F_k(X), with F_k the outward plane of the rest face opposite
  /// corner k: the interpolation of world's values at the current corners, times six times the
  /// rest volume. So Q(X) has the sign of world(phi(X)), and on a face of the tet it depends only
  /// on that face's corners: tets sharing a face and its current corners agree on it exactly.
  /// Zero coefficients (a current tet flat within `world`) must be rejected by the caller.
  static Plane pulled_back(const Plane& world, const std::array<Vec3, 4>& rest, const std::array<Vec3, 4>& current,
                           std::int64_t world_key = -1);
  /// The same plane with the opposite normal.
  Plane flipped() const;

  Kind kind() const { return kind_; }
  /// Whether this is a flipped copy of the plane as defined.
  bool is_flipped() const { return flipped_; }
  int axis() const { return axis_; }
  /// Defining points: three for kThroughPoints, the first two for kWall, none for kPulledBack.
  const std::array<Vec3, 3>& points() const { return points_; }
  int num_defining_points() const { return kind_ == Kind::kThroughPoints ? 3 : kind_ == Kind::kWall ? 2 : 0; }
  /// Coefficients (nx, ny, nz, d) with error bounds.
  const std::array<Approx, 4>& approx() const { return approx_; }
  /// Whether the filtered coefficients are certainly all zero (a degenerate pull-back).
  bool certainly_zero() const;

  /// Rounded coefficients, for output geometry only.
  Eigen::Vector4d rounded() const;

  /// The exact form, computed afresh (callers cache it).
  ExactPlane exact() const;

  /// For a pulled-back plane: the world plane, the tet's rest and current corners, and the
  /// caller's key naming the world plane (pulled-back planes with the same key come from the same
  /// world plane; -1: no key). Null for the other kinds.
  struct PullBack;
  const PullBack* pull_back() const { return pull_back_.get(); }

 private:
  void compute_approx();

  Kind kind_ = Kind::kThroughPoints;
  std::int8_t axis_ = 0;
  bool flipped_ = false;
  std::array<Vec3, 3> points_{};
  std::array<Approx, 4> approx_{};
  std::shared_ptr<const PullBack> pull_back_;
};

struct Plane::PullBack {
  Plane world;
  std::array<Vec3, 4> rest;
  std::array<Vec3, 4> current;
  std::int64_t world_key = -1;
};

/// Sign of n . x + d for an input point x. Exact.
int side_of_point(const Plane& plane, const Vec3& x);

/// Sign of det3 of the three normals: non-zero iff the planes meet in exactly one point. Exact.
int normal_determinant_sign(const Plane& a, const Plane& b, const Plane& c);

/// Sign of det4 of the rows (n, d) of a, b, c, q. Exact.
int plane_determinant_sign(const Plane& a, const Plane& b, const Plane& c, const Plane& q);

/// Side of the point where a, b and c meet, relative to q. `orientation` must be
/// normal_determinant_sign(a, b, c) (non-zero); callers cache it with the point.
inline int side_of_tpi(const Plane& a, const Plane& b, const Plane& c, int orientation, const Plane& q) {
  return plane_determinant_sign(a, b, c, q) * orientation;
}

/// Sign of component `axis` of the plane's normal. Exact.
int normal_component_sign(const Plane& plane, int axis);

/// The axis along which a triangle's walls (virtual triangles) are built: the one on which the
/// plane's normal is largest, chosen on rounded values, and checked non-zero exactly, so walls
/// along it are never parallel to the plane. The plane must not be degenerate.
int wall_axis(const Plane& plane);

/// True when p and q are the same set of points (either orientation). Exact.
bool same_plane(const Plane& p, const Plane& q);
/// +1 when same_plane and the normals point the same way, -1 when opposite, 0 when not the same plane.
int plane_alignment(const Plane& p, const Plane& q);

/// Homogeneous coordinates (X, Y, Z, W) of the point where a, b and c meet, with error bounds: the
/// point is (X, Y, Z) / W. W is det3 of the three normals (non-zero for a point), and by Cramer's
/// rule X, Y, Z are det3 of the normals with one column replaced by -d. For every plane q,
/// q.n . (X, Y, Z) + q.d W = det4[a; b; c; q], so a side test on a cached point is a four-term dot
/// product (the indirect-predicate idea of Attene and Cherchi et al.).
using Homogeneous = std::array<Approx, 4>;
Homogeneous tpi_homogeneous(const Plane& a, const Plane& b, const Plane& c);

/// Homogeneous coordinates (x, y, z, 1) of an input point: exact.
Homogeneous explicit_homogeneous(const Vec3& x);

/// Side of the point where a, b and c meet relative to q, filtered on the cached homogeneous
/// coordinates `h` of that point and exact when the filter cannot decide. `orientation` is
/// normal_determinant_sign(a, b, c).
int side_of_tpi(const Plane& a, const Plane& b, const Plane& c, const Homogeneous& h, int orientation, const Plane& q);

/// Side of an input point x relative to q, filtered on the homogeneous coordinates of x (see
/// explicit_homogeneous) and exact otherwise.
int side_of_point(const Plane& q, const Vec3& x, const Homogeneous& h);

/// Largest error of a rounded coordinate from tpi_coordinates, relative to the point's largest
/// coordinate: 2^-40 (about 1e-12), far below anything a viewer or a simulation resolves. Beyond it
/// the exact evaluation is used. No exact decision depends on it; the one other use is the cell
/// box filter (CellComplex), which widens rounded corners by twice this bound so that a box that
/// misses a triangle certainly does (the first-order bound and final roundings fit in the factor 2).
inline constexpr double kCoordinateTolerance = 0x1p-40;

/// Coordinates of the point where a, b and c meet, correctly rounded or nearly so: from the
/// filtered homogeneous coordinates when their error bound is tiny, otherwise from an exact
/// rational evaluation. For output and volumes only, never for decisions.
Vec3 tpi_coordinates(const Plane& a, const Plane& b, const Plane& c);
Vec3 tpi_coordinates(const Plane& a, const Plane& b, const Plane& c, const Homogeneous& h);

/// Side of q at the point where segment [a, b] meets plane p, for input points a and b strictly on
/// opposite sides of p: sign(q(a) p(b) - p(a) q(b)) * sign(p(b)), from the plane values at the
/// endpoints (x = a + t (b - a) with t = p(a) / (p(a) - p(b))). Exact.
int side_of_segment_meet(const Vec3& a, const Vec3& b, const Plane& p, const Plane& q);

// Exact forms for caching. Signs of the predicates do not change when a plane's coefficients, or
// a point's homogeneous coordinates, are multiplied by a positive number, so each plane and each
// point is scaled to integers on its own.

/// Same as plane.exact().
inline ExactPlane exact_plane(const Plane& plane) { return plane.exact(); }

/// Homogeneous coordinates (X, Y, Z, W) with W > 0, as integers: the point is (X, Y, Z) / W.
using ExactPoint = std::array<mpz_class, 4>;
ExactPoint exact_point(const Vec3& x);
/// The point where three planes meet (they must meet in exactly one point).
ExactPoint exact_tpi(const ExactPlane& a, const ExactPlane& b, const ExactPlane& c);
/// Sign of the plane at the point: sign(n . (X, Y, Z) + d W).
int exact_side(const ExactPlane& plane, const ExactPoint& point);
/// Coordinates of an exact point, each within a few units in the last place (no gcd needed).
Vec3 rounded_exact(const ExactPoint& point);
/// Rational coordinates of an exact point.
std::array<mpq_class, 3> exact_coordinates(const ExactPoint& point);

/// Rounded coordinates from filtered homogeneous coordinates, when their error bound is within
/// kCoordinateTolerance; false otherwise (then round exact_coordinates instead).
bool rounded_coordinates(const Homogeneous& h, Vec3* x);

}  // namespace tetcut::geometry
