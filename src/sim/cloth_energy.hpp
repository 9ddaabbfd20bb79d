#pragma once
// The energies of cloth: a membrane per triangle copy and a bending hinge per shared edge.
//
// Membrane: St. Venant-Kirchhoff in plane stress. F = [x1 - x0, x2 - x0] Dm^-1 (3 x 2) maps the
// rest plane to the world, E = (F^T F - I) / 2, psi = mu |E|^2 + (lambda / 2) tr(E)^2, and the
// energy is the rest area (times the copy's material fraction) times psi. Its Hessian is not
// positive semi-definite under compression, so Newton uses a projection: the negative
// eigenvalues of d2psi/dF2 (6 x 6) clamped to zero.
//
// Bending: the quadratic model for a flat rest state (Bergou, Wardetzky, Harmon, Zorin, Grinspun
// 2006). Over the hinge of an edge (x0, x1) with wings x2, x3 the vector b = sum_i k_i x_i vanishes
// for every affine image of the rest positions exactly when k is their affine dependency,
// k = (A(1,2,3), -A(0,2,3), A(0,1,3), -A(0,1,2)) in signed rest areas. Scaled so that folding one
// wing by a small angle theta costs the discrete-shells energy 3 k_b theta^2 |e|^2 / (A1 + A2),
// the energy is w |b|^2 with w = 3 k_b |e|^4 / (4 A1^2 A2^2 (A1 + A2)): quadratic in the
// positions, with a constant positive semi-definite Hessian 2 w k k^T (x) I. It is exact for
// isometric bending (what inextensible cloth does) and needs no angle, so no singular cases.

#include <tetcut/types.hpp>

#include <Eigen/Core>

#include <array>

namespace tetcut::sim::detail {

using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;

struct MembraneElement {
  /// dF/dx: F = sum_a x_a shape[a]^T, shape[0] = -(shape[1] + shape[2]).
  std::array<Eigen::Vector2d, 3> shape;
  double area = 0;  ///< rest area times the material fraction
};

/// From the rest corners (counter-clockwise) and the area weight (material fraction).
MembraneElement make_membrane(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, double fraction);

/// Energy at corners x; adds its gradient (9, corner-major) and Hessian when not null. With
/// `project`, the Hessian is projected to positive semi-definite.
double membrane_energy(const MembraneElement& e, double mu, double lambda, const std::array<Vec3, 3>& x, Vec9* gradient,
                       Mat9* hessian, bool project);

struct Hinge {
  std::array<Index, 4> nodes{};  ///< edge (0, 1), wings 2 and 3
  std::array<double, 4> k{};
  double weight = 0;
};

/// From the four rest positions (edge first, then the wings) and k_b (times the material share).
Hinge make_hinge(const std::array<Index, 4>& nodes, const std::array<Eigen::Vector2d, 4>& rest, double bending_stiffness);

/// w |sum k_i x_i|^2.
double hinge_energy(const Hinge& h, const std::array<Vec3, 4>& x, Eigen::Matrix<double, 12, 1>* gradient);

}  // namespace tetcut::sim::detail
