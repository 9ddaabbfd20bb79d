#include "sim/svd3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace tetcut::sim::detail {
namespace {

// Cyclic Jacobi needs at most about 6 sweeps for a 3 x 3 matrix to reach rounding (its convergence
// is quadratic); the cap only guards against a tolerance set below rounding.
constexpr int kMaxSweeps = 12;

}  // namespace

void symmetric_eigen3(const Mat3& a, double tolerance, Mat3* vectors, Vec3* values) {
  Mat3& V = *vectors;
  Mat3 d = V.transpose() * a * V;
  d = 0.5 * (d + d.transpose());
  const double tolerance_squared = tolerance * tolerance;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    const double off = d(0, 1) * d(0, 1) + d(0, 2) * d(0, 2) + d(1, 2) * d(1, 2);
    const double diagonal = d(0, 0) * d(0, 0) + d(1, 1) * d(1, 1) + d(2, 2) * d(2, 2);
    if (!(off > tolerance_squared * diagonal)) break;  // also stops on NaN
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        const double apq = d(p, q);
        if (apq == 0) continue;
        // The rotation that zeroes d(p, q): t = tan(angle), the smaller root, so |angle| <= pi/4.
        const double tau = 0.5 * (d(q, q) - d(p, p));
        const double t = (tau >= 0 ? apq : -apq) / (std::abs(tau) + std::sqrt(tau * tau + apq * apq));
        const double c = 1 / std::sqrt(1 + t * t), s = t * c;
        d(p, p) -= t * apq;
        d(q, q) += t * apq;
        d(p, q) = d(q, p) = 0;
        const int r = 3 - p - q;
        const double drp = d(r, p), drq = d(r, q);
        d(r, p) = d(p, r) = c * drp - s * drq;
        d(r, q) = d(q, r) = s * drp + c * drq;
        for (int k = 0; k < 3; ++k) {
          const double vkp = V(k, p), vkq = V(k, q);
          V(k, p) = c * vkp - s * vkq;
          V(k, q) = s * vkp + c * vkq;
        }
      }
    }
  }
  // Descending order; a swap of two columns is a reflection, so one of them changes sign to keep
  // V a rotation.
  Vec3 lambda = d.diagonal();
  const auto order = [&](int i, int j) {
    if (lambda[i] < lambda[j]) {
      std::swap(lambda[i], lambda[j]);
      const Vec3 column = V.col(i);
      V.col(i) = V.col(j);
      V.col(j) = -column;
    }
  };
  order(0, 1);
  order(0, 2);
  order(1, 2);
  *values = lambda;
}

Svd3 svd3(const Mat3& F, double tolerance, const Mat3* v_guess) {
  Svd3 out;
  out.V = v_guess ? *v_guess : Mat3::Identity();
  // Scaled to entries of order one, so that the squared column lengths below neither underflow
  // nor overflow.
  const double scale = F.cwiseAbs().maxCoeff();
  if (!(scale > 0) || !std::isfinite(scale)) {
    out.U = Mat3::Identity();
    out.sigma = Vec3::Constant(scale == 0 ? 0.0 : std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  // One-sided (Hestenes) Jacobi: rotate pairs of columns of B = F V until they are orthogonal.
  // Working on B rather than on F^T F keeps small singular values accurate relative to
  // themselves (squaring would lose them below 1e-8 of the largest).
  Mat3 B = (F / scale) * out.V;
  Mat3& V = out.V;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool rotated = false;
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        const double alpha = B.col(p).squaredNorm(), beta = B.col(q).squaredNorm(), gamma = B.col(p).dot(B.col(q));
        if (!(gamma * gamma > tolerance * tolerance * alpha * beta)) continue;
        rotated = true;
        // The rotation making columns p and q orthogonal: t = tan(angle), the root of
        // t^2 gamma + t (beta - alpha) - gamma = 0 of smaller size (|angle| <= pi/4).
        const double d = beta - alpha;
        const double t = 2 * gamma * (d >= 0 ? 1.0 : -1.0) / (std::abs(d) + std::sqrt(d * d + 4 * gamma * gamma));
        const double c = 1 / std::sqrt(1 + t * t), s = t * c;
        for (Mat3* m : {&B, &V}) {
          const Vec3 mp = m->col(p), mq = m->col(q);
          m->col(p) = c * mp - s * mq;
          m->col(q) = s * mp + c * mq;
        }
      }
    }
    if (!rotated) break;
  }
  // Columns by decreasing length; swapping two is a reflection, so one of them changes sign to
  // keep V a rotation.
  Vec3 length(B.col(0).squaredNorm(), B.col(1).squaredNorm(), B.col(2).squaredNorm());
  const auto order = [&](int i, int j) {
    if (length[i] < length[j]) {
      std::swap(length[i], length[j]);
      for (Mat3* m : {&B, &V}) {
        const Vec3 column = m->col(i);
        m->col(i) = m->col(j);
        m->col(j) = -column;
      }
    }
  };
  order(0, 1);
  order(0, 2);
  order(1, 2);
  // U by Gram-Schmidt on the columns, largest first, orthogonalised twice so that a nearly
  // singular F still gives orthonormal columns; the last is u0 x u1, so U is a rotation and
  // the last singular value takes det F's sign. A column with no length left is completed to an
  // orthonormal basis.
  const double s0 = B.col(0).norm();
  const Vec3 u0 = s0 > 0 ? Vec3(B.col(0) / s0) : Vec3::UnitX();
  Vec3 c1 = B.col(1) - u0.dot(B.col(1)) * u0;
  c1 -= u0.dot(c1) * u0;
  const double s1 = c1.norm();
  const Vec3 u1 = s1 > 0 ? Vec3(c1 / s1) : Vec3(u0.unitOrthogonal());
  const Vec3 u2 = u0.cross(u1);
  out.U.col(0) = u0;
  out.U.col(1) = u1;
  out.U.col(2) = u2;
  out.sigma = scale * Vec3(s0, s1, u2.dot(B.col(2)));
  return out;
}

}  // namespace tetcut::sim::detail
