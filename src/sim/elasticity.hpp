#pragma once
// Isotropic hyperelastic energies in closed form: their stress, and the eigensystem of their
// stress derivative dP/dF, so that projecting the Hessian to positive semi-definite needs no
// numerical 9 x 9 eigen-decomposition (Smith, De Goes, Kim 2019, "Analytic eigensystems for
// isotropic distortion energies").
//
// With F = U diag(sigma) V^T (rotation-variant SVD) and, for each axis k, (i, j) the other two:
//   twist k:  U (e_i e_j^T - e_j e_i^T) V^T / sqrt 2, eigenvalue (Psi_i + Psi_j) / (sigma_i + sigma_j)
//   flip k:   U (e_i e_j^T + e_j e_i^T) V^T / sqrt 2, eigenvalue (Psi_i - Psi_j) / (sigma_i - sigma_j)
//   scaling:  U diag(s) V^T, where dP/dF acts as the 3 x 3 Hessian d^2 Psi / d sigma^2
// (Psi_i = dPsi / dsigma_i). Both models are written so that these need no division by a
// difference of singular values: stable Neo-Hookean through the invariants I_C = |F|^2 and
// J = det F, corotated through the singular values.
//
// Everything here is O(1) per element and allocation-free: it is the inner loop of the simulator.

#include "sim/svd3.hpp"

#include <tetcut/sim.hpp>

#include <array>

namespace tetcut::sim::detail {

using Vec9 = Eigen::Matrix<double, 9, 1>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
/// dF/dx of a tet: F = sum_a x_a w_a^T, row a is w_a (stored row by row, as the lane kernel
/// reads it).
using ShapeWeights = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;

/// Corotated's twist eigenvalue has 4 mu / (sigma_i + sigma_j): where the two singular values
/// nearly cancel (an element inverted through an edge), the polar rotation is not differentiable
/// and the term is unbounded. Within this distance of that fold the twist is given no stiffness,
/// as a projection would clamp the large negative value to.
inline constexpr double kRotationFold = 1e-8;

/// dP/dF at F, as its eigensystem in the frame of `svd` (F's rotation-variant SVD).
struct StressEigensystem {
  Vec3 twist, flip;  ///< eigenvalue of the twist and flip about axis k (see above)
  Mat3 scaling;      ///< d^2 Psi / d sigma^2, symmetric
};
StressEigensystem stress_eigensystem(Model model, const Lame& p, const Svd3& svd);

/// C with C C^T the positive semi-definite part of the symmetric `a` (eigenvalues clamped at
/// zero): the Cholesky factor when `a` is positive definite (the common case, no eigensolver),
/// otherwise eigenvectors scaled by the square roots of the clamped eigenvalues.
Mat3 positive_part_factor(const Mat3& a);

/// Psi(F), and P(F) = dPsi/dF when `stress` is not null. Corotated needs F's polar rotation;
/// pass `svd` when it is known, otherwise it is computed.
double energy_and_stress(Model model, const Lame& p, const Mat3& F, Mat3* stress, const Svd3* svd = nullptr);

/// The deformation gradient of a tet from its four current node positions.
inline Mat3 deformation_gradient(const ShapeWeights& w, const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  return x0 * w.row(0) + x1 * w.row(1) + x2 * w.row(2) + x3 * w.row(3);
}
/// The same from node positions stored 3 per node (`x`, node-major) and the tet's nodes.
inline Mat3 deformation_gradient(const ShapeWeights& w, const double* x, const std::array<Index, 4>& nodes) {
  Mat3 F = Mat3::Zero();
  for (int a = 0; a < 4; ++a) {
    const double* p = x + 3 * static_cast<std::size_t>(nodes[a]);
    for (int j = 0; j < 3; ++j) {
      const double wj = w(a, j);
      F(0, j) += p[0] * wj;
      F(1, j) += p[1] * wj;
      F(2, j) += p[2] * wj;
    }
  }
  return F;
}

/// The gradient of volume * Psi with respect to the tet's 12 node coordinates, from P.
inline Vec12 element_gradient(const ShapeWeights& w, double volume, const Mat3& P) {
  Vec12 g;
  for (int a = 0; a < 4; ++a) g.segment<3>(3 * a) = volume * (P * w.row(a).transpose());
  return g;
}

/// A factor Q of the element Hessian, H = Q Q^T: row 3a + i for node a, coordinate i; a column
/// per eigenmatrix of dP/dF.
using HessianFactor = Eigen::Matrix<double, 12, 9, Eigen::RowMajor>;

/// The projected Hessian of volume * Psi(F(x)) with respect to the tet's 12 node coordinates
/// (node-major, x y z) as a factor: the columns of Q are sqrt(volume lambda+) B^T m over the
/// eigenmatrices m of dP/dF (eigenvalues lambda, clamped at zero), where (B^T m)_a = m w_a. So H
/// is positive semi-definite by construction, however accurate the SVD. `v_guess` warm starts the
/// SVD (the element's V from its last Hessian) and receives the new V. Returns the energy
/// density; `stress` receives P. About 600 flops.
double element_hessian_factor(Model model, const Lame& p, const Mat3& F, const ShapeWeights& w, double volume, Mat3* v_guess,
                              Mat3* stress, HessianFactor* q);
/// The same as a 12 x 12 matrix (for tests and small uses).
double element_hessian(Model model, const Lame& p, const Mat3& F, const ShapeWeights& w, double volume, Mat3* v_guess,
                       Mat3* stress, Mat12* hessian);
/// Block (a, b) of Q Q^T, 3 x 3 row-major: rows 3a.. of Q times rows 3b.. transposed.
inline void factor_block(const HessianFactor& q, int a, int b, double* out) {
  for (int r = 0; r < 3; ++r) {
    const double* qa = q.data() + 9 * (3 * a + r);
    for (int c = 0; c < 3; ++c) {
      const double* qb = q.data() + 9 * (3 * b + c);
      double sum = 0;
      for (int m = 0; m < 9; ++m) sum += qa[m] * qb[m];
      out[3 * r + c] = sum;
    }
  }
}

}  // namespace tetcut::sim::detail
