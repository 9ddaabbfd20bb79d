// The element Hessian kernel of sim/elasticity on four elements at once, one per lane of an AVX
// register (see element_batch.hpp for why). This file alone is compiled with -mavx2 -mfma, and
// it is called only when the processor has both (element_lanes_available). It includes no Eigen
// and no other header with inline functions, so no AVX instance of a shared inline function can
// be picked by the linker for code that runs on a processor without AVX.

#include "sim/element_batch.hpp"

#include <immintrin.h>

#include <cmath>
#include <limits>

// Vectors of four doubles are passed by value between this file's own functions only, so the
// calling convention GCC warns about never crosses a library boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace tetcut::sim::detail {
namespace {

constexpr int kLanes = kLaneBatch;
// kLanes doubles in one GCC/Clang vector: arithmetic, comparisons (a mask of -1 and 0 per lane)
// and selects (mask ? a : b) compile to vector instructions, SSE2 pairs or AVX quads.
using Lanes = double __attribute__((vector_size(8 * kLanes)));
using Mask = long long __attribute__((vector_size(8 * kLanes)));
static_assert(kLanes == 4, "one AVX register of doubles");

Lanes broadcast(double x) { return Lanes{} + x; }
Lanes select(Mask m, Lanes a, Lanes b) { return m ? a : b; }
Lanes abs(Lanes a) { return a < 0 ? -a : a; }
Lanes max(Lanes a, Lanes b) { return a > b ? a : b; }
bool any(Mask m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }
Lanes sqrt(Lanes a) { return _mm256_sqrt_pd(a); }
Lanes log(Lanes a) { return Lanes{std::log(a[0]), std::log(a[1]), std::log(a[2]), std::log(a[3])}; }

// A 3 x 3 matrix and a 3-vector of lanes, m[row][column].
struct LaneMatrix {
  Lanes m[3][3];
};
struct LaneVector {
  Lanes v[3];
};

Lanes dot(const LaneVector& a, const LaneVector& b) { return a.v[0] * b.v[0] + a.v[1] * b.v[1] + a.v[2] * b.v[2]; }
LaneVector column(const LaneMatrix& a, int c) { return {{a.m[0][c], a.m[1][c], a.m[2][c]}}; }
LaneVector cross(const LaneVector& a, const LaneVector& b) {
  return {{a.v[1] * b.v[2] - a.v[2] * b.v[1], a.v[2] * b.v[0] - a.v[0] * b.v[2], a.v[0] * b.v[1] - a.v[1] * b.v[0]}};
}

constexpr int kPairs[3][2] = {{1, 2}, {0, 2}, {0, 1}};
constexpr int kBlockRow[10] = {0, 0, 0, 0, 1, 1, 1, 2, 2, 3};
constexpr int kBlockColumn[10] = {0, 1, 2, 3, 1, 2, 3, 2, 3, 3};
// Cyclic Jacobi sweeps at most; as in svd3, a guard only.
constexpr int kMaxSweeps = 12;

// Rotates columns p and q of a by (c, s): a_p <- c a_p - s a_q, a_q <- s a_p + c a_q.
void rotate(LaneMatrix* a, int p, int q, const Lanes& c, const Lanes& s) {
  for (int r = 0; r < 3; ++r) {
    const Lanes ap = a->m[r][p], aq = a->m[r][q];
    a->m[r][p] = c * ap - s * aq;
    a->m[r][q] = s * ap + c * aq;
  }
}

// Swaps columns i and j where `swap` holds, negating the one moved to j (a swap alone would be a
// reflection).
void swap_columns(LaneMatrix* a, int i, int j, const Mask& swap) {
  for (int r = 0; r < 3; ++r) {
    const Lanes ai = a->m[r][i], aj = a->m[r][j];
    a->m[r][i] = select(swap, aj, ai);
    a->m[r][j] = select(swap, -ai, aj);
  }
}

// The rotation-variant SVD as in svd3, lane by lane: one-sided Jacobi on B = (F / scale) V, V
// warm-started. Lanes it cannot take (zero, non-finite or rank-one F) are marked in `fallback`.
void lane_svd(const LaneMatrix& F, double tolerance, LaneMatrix* V_io, LaneMatrix* U_out, Lanes* sigma_out, Mask* fallback_io) {
  LaneMatrix& V = *V_io;
  Mask& fallback = *fallback_io;
  Lanes scale = broadcast(0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) scale = max(scale, abs(F.m[r][c]));
  }
  fallback = fallback || !(scale > 0 && scale < std::numeric_limits<double>::infinity());
  const Lanes inverse = select(fallback, broadcast(1), 1 / scale);
  LaneMatrix B;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      Lanes sum = broadcast(0);
      for (int k = 0; k < 3; ++k) sum += select(fallback, broadcast(r == k ? 1.0 : 0.0), F.m[r][k] * inverse) * V.m[k][c];
      B.m[r][c] = sum;
    }
  }
  const double tolerance_squared = tolerance * tolerance;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool rotated = false;
    for (int pq = 2; pq >= 0; --pq) {  // pairs (0,1), (0,2), (1,2)
      const int i = kPairs[pq][0], j = kPairs[pq][1];
      const LaneVector bi = column(B, i), bj = column(B, j);
      const Lanes alpha = dot(bi, bi), beta = dot(bj, bj), gamma = dot(bi, bj);
      const Mask need = gamma * gamma > tolerance_squared * alpha * beta;
      if (!any(need)) continue;
      rotated = true;
      const Lanes d = beta - alpha;
      const Lanes sign = select(d >= 0, broadcast(1), broadcast(-1));
      const Lanes t = select(need, 2 * gamma * sign / (abs(d) + sqrt(d * d + 4 * gamma * gamma)), broadcast(0));
      const Lanes c = 1 / sqrt(1 + t * t), s = t * c;
      rotate(&B, i, j, c, s);
      rotate(&V, i, j, c, s);
    }
    if (!rotated) break;
  }
  Lanes length[3];
  for (int k = 0; k < 3; ++k) length[k] = dot(column(B, k), column(B, k));
  const auto order = [&](int i, int j) {
    const Mask swap = length[i] < length[j];
    const Lanes li = length[i];
    length[i] = select(swap, length[j], li);
    length[j] = select(swap, li, length[j]);
    swap_columns(&B, i, j, swap);
    swap_columns(&V, i, j, swap);
  };
  order(0, 1);
  order(0, 2);
  order(1, 2);
  const LaneVector b0 = column(B, 0), b1 = column(B, 1), b2 = column(B, 2);
  const Lanes s0 = sqrt(dot(b0, b0));
  fallback = fallback || !(s0 > 0);
  const Lanes s0_safe = select(fallback, broadcast(1), s0);
  LaneVector u0, u1;
  for (int r = 0; r < 3; ++r) u0.v[r] = b0.v[r] / s0_safe;
  LaneVector c1 = b1;
  for (int pass = 0; pass < 2; ++pass) {
    const Lanes along = dot(u0, c1);
    for (int r = 0; r < 3; ++r) c1.v[r] -= along * u0.v[r];
  }
  const Lanes s1 = sqrt(dot(c1, c1));
  fallback = fallback || !(s1 > 0);  // rank one: completed to a basis by the scalar kernel
  const Lanes s1_safe = select(fallback, broadcast(1), s1);
  for (int r = 0; r < 3; ++r) u1.v[r] = c1.v[r] / s1_safe;
  const LaneVector u2 = cross(u0, u1);
  LaneMatrix& U = *U_out;
  for (int r = 0; r < 3; ++r) {
    U.m[r][0] = u0.v[r];
    U.m[r][1] = u1.v[r];
    U.m[r][2] = u2.v[r];
  }
  sigma_out[0] = scale * s0;
  sigma_out[1] = scale * s1;
  sigma_out[2] = scale * dot(u2, b2);

}

}  // namespace

void element_hessian_lanes(const LaneMaterial& p, LaneBatch* io, int count) {
  // Pack: lanes past `count` repeat lane 0 (valid data; their results are dropped).
  LaneMatrix F, V;
  Lanes w[4][3], volume;
  for (int lane = 0; lane < kLanes; ++lane) {
    const int from = lane < count ? lane : 0;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        F.m[r][c][lane] = io->F[from][3 * r + c];
        V.m[r][c][lane] = io->V[from][3 * c + r];
      }
    }
    for (int a = 0; a < 4; ++a) {
      for (int c = 0; c < 3; ++c) w[a][c][lane] = io->weights[from][3 * a + c];
    }
    volume[lane] = io->volume[from];
  }
  const double tolerance = p.svd_tolerance;

  // The SVD: for corotated's polar rotation, or for the Hessian's eigensystem; stable
  // Neo-Hookean's energy and stress need none.
  Mask fallback = F.m[0][0] != F.m[0][0];  // all false
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) fallback = fallback || !(abs(F.m[r][c]) < std::numeric_limits<double>::infinity());
  }
  LaneMatrix U;
  Lanes sigma[3] = {broadcast(0), broadcast(0), broadcast(0)};
  if (p.corotated || io->with_hessian) lane_svd(F, tolerance, &V, &U, sigma, &fallback);

  // Energy density and stress.
  LaneMatrix cofactor;
  {
    const LaneVector f0 = column(F, 0), f1 = column(F, 1), f2 = column(F, 2);
    const LaneVector c0 = cross(f1, f2), c1v = cross(f2, f0), c2 = cross(f0, f1);
    for (int r = 0; r < 3; ++r) {
      cofactor.m[r][0] = c0.v[r];
      cofactor.m[r][1] = c1v.v[r];
      cofactor.m[r][2] = c2.v[r];
    }
  }
  LaneMatrix P;
  Lanes energy;
  Lanes twist[3], flip[3], scaling[3][3];
  const Lanes J = sigma[0] * sigma[1] * sigma[2];
  const Lanes g[3] = {sigma[1] * sigma[2], sigma[0] * sigma[2], sigma[0] * sigma[1]};  // dJ/dsigma
  if (!p.corotated) {
    const double alpha = 1 + 0.75 * p.mu / p.lambda;
    Lanes ic = broadcast(0);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) ic += F.m[r][c] * F.m[r][c];
    }
    const Lanes det = dot(column(F, 0), column(cofactor, 0));
    const Lanes identity = p.mu * (1 - 1 / (ic + 1));  // 2 dPsi/dI_C
    const Lanes stretch = p.lambda * (det - alpha);           // dPsi/dJ, from F
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) P.m[r][c] = identity * F.m[r][c] + stretch * cofactor.m[r][c];
    }
    const double at_rest = 0.5 * p.lambda * (1 - alpha) * (1 - alpha) - 0.5 * p.mu * std::log(4.0);
    energy = 0.5 * p.mu * (ic - 3) + 0.5 * p.lambda * (det - alpha) * (det - alpha) - 0.5 * p.mu * log(ic + 1) - at_rest;
    // The eigensystem from the singular values (as stress_eigensystem).
    const Lanes ic_sigma = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2];
    const Lanes identity_sigma = p.mu * (1 - 1 / (ic_sigma + 1));
    const Lanes volume_term = p.lambda * (J - alpha);
    const Lanes curvature = 2 * p.mu / ((ic_sigma + 1) * (ic_sigma + 1));
    for (int k = 0; k < 3; ++k) {
      twist[k] = identity_sigma + volume_term * sigma[k];
      flip[k] = identity_sigma - volume_term * sigma[k];
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) scaling[i][j] = curvature * sigma[i] * sigma[j] + p.lambda * g[i] * g[j] + (i == j ? identity_sigma : broadcast(0));
    }
    for (int k = 0; k < 3; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      scaling[i][j] += volume_term * sigma[k];
      scaling[j][i] += volume_term * sigma[k];
    }
  } else {
    const Lanes volume_term = p.lambda * (J - 1);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const Lanes rotation = U.m[r][0] * V.m[c][0] + U.m[r][1] * V.m[c][1] + U.m[r][2] * V.m[c][2];
        P.m[r][c] = 2 * p.mu * (F.m[r][c] - rotation) + volume_term * cofactor.m[r][c];
      }
    }
    energy = p.mu * ((sigma[0] - 1) * (sigma[0] - 1) + (sigma[1] - 1) * (sigma[1] - 1) + (sigma[2] - 1) * (sigma[2] - 1)) +
             0.5 * p.lambda * (J - 1) * (J - 1);
    const double kRotationFold = p.rotation_fold;
    for (int k = 0; k < 3; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      const Lanes sum = sigma[i] + sigma[j];
      const Mask smooth = abs(sum) > kRotationFold;
      twist[k] = select(smooth, 2 * p.mu - 4 * p.mu / select(smooth, sum, broadcast(1)) + volume_term * sigma[k], broadcast(0));
      flip[k] = 2 * p.mu - volume_term * sigma[k];
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) scaling[i][j] = p.lambda * g[i] * g[j] + (i == j ? broadcast(2 * p.mu) : broadcast(0));
    }
    for (int k = 0; k < 3; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      scaling[i][j] += volume_term * sigma[k];
      scaling[j][i] += volume_term * sigma[k];
    }
  }

  if (io->with_hessian) {
    // The scaling block's factor: Cholesky where it is positive definite, else the scalar
    // kernel's eigen-decomposition, lane by lane.
    Lanes factor[3][3];
    {
      const Lanes c00 = sqrt(max(scaling[0][0], broadcast(0)));
      const Lanes c00_safe = select(c00 > 0, c00, broadcast(1));
      const Lanes c10 = scaling[1][0] / c00_safe, c20 = scaling[2][0] / c00_safe;
      const Lanes d1 = scaling[1][1] - c10 * c10;
      const Lanes c11 = sqrt(max(d1, broadcast(0)));
      const Lanes c11_safe = select(c11 > 0, c11, broadcast(1));
      const Lanes c21 = (scaling[2][1] - c20 * c10) / c11_safe;
      const Lanes d2 = scaling[2][2] - c20 * c20 - c21 * c21;
      const Mask definite = scaling[0][0] > 0 && d1 > 0 && d2 > 0;
      factor[0][0] = c00;
      factor[1][0] = c10;
      factor[2][0] = c20;
      factor[0][1] = factor[0][2] = factor[1][2] = broadcast(0);
      factor[1][1] = c11;
      factor[2][1] = c21;
      factor[2][2] = sqrt(max(d2, broadcast(0)));
      // An indefinite scaling block (strong compression): the scalar kernel clamps it.
      fallback = fallback || !definite;
    }

    // The factor Q of the Hessian (as element_hessian_factor), then its 10 distinct blocks.
    const Lanes root_volume = sqrt(volume), half_volume = 0.5 * volume;
    Lanes w_frame[4][3];  // V^T w_a
    for (int a = 0; a < 4; ++a) {
      for (int c = 0; c < 3; ++c) w_frame[a][c] = w[a][0] * V.m[0][c] + w[a][1] * V.m[1][c] + w[a][2] * V.m[2][c];
    }
    Lanes q[12][9];
    for (int k = 0; k < 3; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      const Lanes t = sqrt(half_volume * max(twist[k], broadcast(0))), f = sqrt(half_volume * max(flip[k], broadcast(0)));
      for (int a = 0; a < 4; ++a) {
        for (int r = 0; r < 3; ++r) {
          const Lanes along_i = w_frame[a][j] * U.m[r][i], along_j = w_frame[a][i] * U.m[r][j];
          q[3 * a + r][2 * k] = t * (along_i - along_j);
          q[3 * a + r][2 * k + 1] = f * (along_i + along_j);
        }
      }
    }
    for (int a = 0; a < 4; ++a) {
      for (int r = 0; r < 3; ++r) {
        for (int m = 0; m < 3; ++m) {
          Lanes sum = broadcast(0);
          for (int l = 0; l < 3; ++l) sum += U.m[r][l] * factor[l][m] * w_frame[a][l];
          q[3 * a + r][6 + m] = root_volume * sum;
        }
      }
    }
    for (int b = 0; b < 10; ++b) {
      const int a0 = kBlockRow[b], a1 = kBlockColumn[b];
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          Lanes sum = broadcast(0);
          for (int m = 0; m < 9; ++m) sum += q[3 * a0 + r][m] * q[3 * a1 + c][m];
          for (int lane = 0; lane < count; ++lane) io->blocks[lane][b][3 * r + c] = sum[lane];
        }
      }
    }
  }
  for (int a = 0; a < 4; ++a) {
    for (int r = 0; r < 3; ++r) {
      const Lanes gradient = volume * (P.m[r][0] * w[a][0] + P.m[r][1] * w[a][1] + P.m[r][2] * w[a][2]);
      for (int lane = 0; lane < count; ++lane) io->gradient[lane][3 * a + r] = gradient[lane];
    }
  }
  for (int lane = 0; lane < count; ++lane) {
    io->energy[lane] = energy[lane];
    io->fallback[lane] = fallback[lane] != 0;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) io->V[lane][3 * c + r] = V.m[r][c][lane];
    }
  }
}

}  // namespace tetcut::sim::detail
