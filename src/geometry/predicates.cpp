#include "geometry/predicates.hpp"

#include <gmpxx.h>

#include <cmath>
#include <limits>

#include "geometry/approx.hpp"

namespace tetcut::geometry {
namespace {

// Relative forward error of the double evaluation below, as a multiple of the permanent (the
// same expression with every product and difference taken in absolute value). For the
// difference-then-cofactor form the bound is (7 + 56 eps) eps (Shewchuk 1997, "Adaptive Precision
// Floating-Point Arithmetic and Fast Robust Geometric Predicates", section 4.3), eps = 2^-53.
constexpr double kEps = std::numeric_limits<double>::epsilon() / 2;
constexpr double kOrient3dErrorBound = (7.0 + 56.0 * kEps) * kEps;
// The same analysis for the 2x2 determinant (Shewchuk's ccwerrboundA).
constexpr double kOrient2dErrorBound = (3.0 + 16.0 * kEps) * kEps;
// Below this permanent, products may underflow and the relative bound no longer holds.
constexpr double kUnderflowGuard = std::numeric_limits<double>::min() * 1e30;

int sign_of(const mpq_class& v) { return sgn(v); }

}  // namespace

int orient3d_exact(const double* a, const double* b, const double* c, const double* d) {
  mpq_class m[3][3];
  for (int k = 0; k < 3; ++k) {
    m[0][k] = mpq_class(b[k]) - mpq_class(a[k]);
    m[1][k] = mpq_class(c[k]) - mpq_class(a[k]);
    m[2][k] = mpq_class(d[k]) - mpq_class(a[k]);
  }
  const mpq_class det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                        m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                        m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return sign_of(det);
}

int orient3d(const double* a, const double* b, const double* c, const double* d) {
  const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];

  const double cydz = cy * dz, czdy = cz * dy;
  const double cxdz = cx * dz, czdx = cz * dx;
  const double cxdy = cx * dy, cydx = cy * dx;
  const double det = bx * (cydz - czdy) - by * (cxdz - czdx) + bz * (cxdy - cydx);
  const double permanent = std::abs(bx) * (std::abs(cydz) + std::abs(czdy)) +
                           std::abs(by) * (std::abs(cxdz) + std::abs(czdx)) +
                           std::abs(bz) * (std::abs(cxdy) + std::abs(cydx));
  const double bound = kOrient3dErrorBound * permanent;
  // The bound assumes no overflow or underflow; a non-finite or subnormal-range permanent goes to
  // the exact path, which has neither problem.
  if (std::isfinite(permanent) && permanent > kUnderflowGuard) {
    if (det > bound) return 1;
    if (-det > bound) return -1;
  }
  // Second stage: the same determinant with the rounding errors actually committed; it settles
  // exact zeros of exactly representable configurations (grid-aligned points) without GMP.
  Approx m[3][3];
  for (int k = 0; k < 3; ++k) {
    m[0][k] = Approx::exact(b[k]) - Approx::exact(a[k]);
    m[1][k] = Approx::exact(c[k]) - Approx::exact(a[k]);
    m[2][k] = Approx::exact(d[k]) - Approx::exact(a[k]);
  }
  const int s = certain_sign(m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                             m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                             m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]));
  if (s != 2) return s;
  return orient3d_exact(a, b, c, d);
}

int orient2d(const double* a, const double* b, const double* c) {
  const double left = (b[0] - a[0]) * (c[1] - a[1]);
  const double right = (b[1] - a[1]) * (c[0] - a[0]);
  const double det = left - right;
  const double permanent = std::abs(left) + std::abs(right);
  if (std::isfinite(permanent) && permanent > kUnderflowGuard) {
    const double bound = kOrient2dErrorBound * permanent;
    if (det > bound) return 1;
    if (-det > bound) return -1;
  }
  const auto e = [](double x) { return Approx::exact(x); };
  const int s = certain_sign((e(b[0]) - e(a[0])) * (e(c[1]) - e(a[1])) - (e(b[1]) - e(a[1])) * (e(c[0]) - e(a[0])));
  if (s != 2) return s;
  const mpq_class exact = (mpq_class(b[0]) - mpq_class(a[0])) * (mpq_class(c[1]) - mpq_class(a[1])) -
                          (mpq_class(b[1]) - mpq_class(a[1])) * (mpq_class(c[0]) - mpq_class(a[0]));
  return sgn(exact);
}

bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double pa[2] = {a[u], a[v]}, pb[2] = {b[u], b[v]}, pc[2] = {c[u], c[v]};
    if (orient2d(pa, pb, pc) != 0) return false;
  }
  return true;
}

}  // namespace tetcut::geometry
