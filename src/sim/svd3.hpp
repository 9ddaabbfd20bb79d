#pragma once
// The rotation-variant singular value decomposition of a 3 x 3 matrix, F = U diag(sigma) V^T with
// U and V rotations (det +1): sigma[0] >= sigma[1] >= |sigma[2]|, and sigma[2] carries the sign of
// det F, so an inverted element has a negative last singular value instead of a reflection in U
// or V. This is the form in which isotropic energies and their eigensystems are written (Irving,
// Teran, Fedkiw 2004; Smith, De Goes, Kim 2019).
//
// One-sided Jacobi rotations of the columns of F V give V; U comes from Gram-Schmidt on F V, so it
// stays a rotation when F is singular. Both factors are orthonormal to rounding whatever the
// number of sweeps; the sweeps only decide how diagonal U^T F V is.

#include <tetcut/sim.hpp>

namespace tetcut::sim::detail {

struct Svd3 {
  Mat3 U, V;
  Vec3 sigma;
};

/// The cosine between two columns of F V at which Jacobi stops: rounding, for the energies that
/// need an exact polar decomposition (corotated). 1e-15 is within a few ulps of a double.
inline constexpr double kSvdExact = 1e-15;
/// Enough for a Newton matrix: the eigenvectors of the Hessian are off by about this much, which
/// changes a step far less than the linear solver's own tolerance does.
inline constexpr double kSvdForHessian = 1e-8;

/// Eigenvectors (columns of `vectors`, a rotation) and eigenvalues (descending) of a symmetric
/// 3 x 3 matrix, by cyclic Jacobi rotations until the off-diagonal part is below `tolerance`
/// times the diagonal's norm. On entry `vectors` is the first guess (a rotation: the identity, or
/// the last answer for a matrix that changed a little, which saves sweeps). O(1): at most 12 sweeps.
void symmetric_eigen3(const Mat3& a, double tolerance, Mat3* vectors, Vec3* values);

/// The rotation-variant SVD, accurate relative to each singular value. `v_guess` (a rotation,
/// e.g. the previous V of the same element) warm starts the Jacobi sweeps; pass nullptr for the
/// identity. O(1): at most 12 sweeps of 3 rotations. A non-finite F gives NaN singular values.
Svd3 svd3(const Mat3& F, double tolerance, const Mat3* v_guess = nullptr);

}  // namespace tetcut::sim::detail
