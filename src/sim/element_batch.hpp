#pragma once
// The element Hessian of sim/elasticity for several tets at once, one per SIMD lane.
//
// The scalar kernel is a chain of square roots and divisions (the Jacobi rotations of the SVD,
// the eigenvalues' square roots): it waits on their latency, one element at a time. The lane
// kernel runs the same arithmetic on four elements in one AVX register, so independent elements
// fill the vector units and hide each other's latency (measured here: 160 ns against 340 ns per
// element on one core). All lanes take the same path: a Jacobi rotation a lane does not need
// has angle zero, a branch is a select. Lanes the fast path cannot take (a zero, non-finite or
// rank-one F; an indefinite scaling block) come back marked, and the caller runs the scalar
// kernel on them, so the results are those of element_hessian_factor up to the SVD's tolerance.
//
// Plain arrays at this boundary: the kernel's translation unit is compiled for AVX2 and FMA and
// must share no inline code with the rest of the library.

namespace tetcut::sim::detail {

inline constexpr int kLaneBatch = 4;

/// The material as the kernel needs it (model_parameters' Lame, the SVD tolerance for the
/// model, corotated's fold distance).
struct LaneMaterial {
  bool corotated = false;
  double mu = 0, lambda = 0;
  double svd_tolerance = 0;
  double rotation_fold = 0;
};

/// F row-major (F[lane][3 r + c]), weights row by row (weights[lane][3 a + c] is w_a's c), V
/// column-major (V[lane][3 c + r], as Eigen stores a Matrix3d).
struct LaneBatch {
  // In.
  double F[kLaneBatch][9];
  double weights[kLaneBatch][12];
  double volume[kLaneBatch];
  double V[kLaneBatch][9];  ///< in: each element's last V (warm start); out: the new one
  bool with_hessian = true;  ///< false: energy and gradient only (the blocks are left alone)
  // Out.
  double energy[kLaneBatch];        ///< Psi(F) per unit volume
  double gradient[kLaneBatch][12];  ///< volume P w_a, node-major
  /// The 10 distinct 3 x 3 blocks (a, b), a <= b, row-major, in the order (0,0) (0,1) (0,2)
  /// (0,3) (1,1) (1,2) (1,3) (2,2) (2,3) (3,3).
  double blocks[kLaneBatch][10][9];
  bool fallback[kLaneBatch];  ///< the scalar kernel must redo this lane (outputs undefined)
};

/// Whether the lane kernel can run here: built for x86-64 and the processor has AVX2 and FMA.
bool element_lanes_available();
/// Lanes 0 .. count - 1 (count 1 .. kLaneBatch). O(1) per element, no allocation. Without the
/// Hessian only a zero, non-finite or rank-one F is handed back.
void element_hessian_lanes(const LaneMaterial& material, LaneBatch* batch, int count);

}  // namespace tetcut::sim::detail
