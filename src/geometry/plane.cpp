#include "geometry/plane.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/predicates.hpp"

namespace tetcut::geometry {
namespace {

template <typename T>
T det3(const T* r0, const T* r1, const T* r2) {
  return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) - r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
         r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
}

// det of the 4x4 matrix with rows a, b, c, q, expanded along q.
template <typename T>
T det4(const std::array<T, 4>& a, const std::array<T, 4>& b, const std::array<T, 4>& c, const std::array<T, 4>& q) {
  T result{};
  bool first = true;
  for (int j = 0; j < 4; ++j) {
    T ra[3], rb[3], rc[3];
    for (int k = 0, m = 0; k < 4; ++k) {
      if (k == j) continue;
      ra[m] = a[k];
      rb[m] = b[k];
      rc[m] = c[k];
      ++m;
    }
    const T term = q[j] * det3(ra, rb, rc);
    // Cofactor sign of entry (3, j) is (-1)^(3 + j).
    if (first) {
      if (j % 2 == 1) {
        result = term;
      } else {
        result = -term;
      }
      first = false;
    } else if (j % 2 == 1) {
      result = result + term;
    } else {
      result = result - term;
    }
  }
  return result;
}

int sign_of(const mpz_class& v) { return sgn(v); }

// Exact coefficients of planes with every input double scaled by 2^scale to an integer.
struct ScaledInputs {
  int scale = std::numeric_limits<int>::min();

  void include(double x) {
    if (x == 0) return;
    int exponent = 0;
    std::frexp(x, &exponent);  // x = m 2^exponent, 0.5 <= |m| < 1: x is a multiple of 2^(exponent - 53)
    scale = std::max(scale, 53 - exponent);
  }
  void include(const Plane& p) {
    const int count = p.kind() == Plane::Kind::kWall ? 2 : 3;
    for (int i = 0; i < count; ++i) {
      for (int k = 0; k < 3; ++k) include(p.points()[i][k]);
    }
  }
  mpz_class integer(double x) const {
    if (x == 0) return 0;
    int exponent = 0;
    const double m = std::frexp(x, &exponent);
    mpz_class result(static_cast<long>(std::ldexp(m, 53)));  // exact: 53-bit mantissa
    const int shift = exponent - 53 + scale;                   // >= 0 by the choice of scale
    mpz_mul_2exp(result.get_mpz_t(), result.get_mpz_t(), static_cast<mp_bitcnt_t>(shift));
    return result;
  }
};

}  // namespace

// Exact plane coefficients on the integer lattice of a ScaledInputs.
struct ExactPlanes {
  static std::array<mpz_class, 4> coefficients(const Plane& plane, const ScaledInputs& s) {
    const auto& pts = plane.points();
    mpz_class p[3], q[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = s.integer(pts[0][k]);
      q[k] = s.integer(pts[1][k]);
    }
    const mpz_class u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    std::array<mpz_class, 4> c;
    if (plane.kind() == Plane::Kind::kThroughPoints) {
      mpz_class w[3];
      for (int k = 0; k < 3; ++k) w[k] = s.integer(pts[2][k]) - p[k];
      c[0] = u[1] * w[2] - u[2] * w[1];
      c[1] = u[2] * w[0] - u[0] * w[2];
      c[2] = u[0] * w[1] - u[1] * w[0];
    } else {
      // u x e_axis
      const int a = plane.axis(), b = (a + 1) % 3, d = (a + 2) % 3;
      c[a] = 0;
      c[b] = u[d];
      c[d] = -u[b];
    }
    c[3] = -(c[0] * p[0] + c[1] * p[1] + c[2] * p[2]);
    if (plane.flipped_) {
      for (auto& v : c) v = -v;
    }
    return c;
  }
};

Plane Plane::through(const Vec3& p, const Vec3& q, const Vec3& r) {
  Plane plane;
  plane.kind_ = Kind::kThroughPoints;
  plane.points_ = {p, q, r};
  plane.compute_approx();
  return plane;
}

Plane Plane::wall(const Vec3& p, const Vec3& q, int axis) {
  Plane plane;
  plane.kind_ = Kind::kWall;
  plane.axis_ = static_cast<std::int8_t>(axis);
  plane.points_ = {p, q, Vec3::Zero()};
  plane.compute_approx();
  return plane;
}

Plane Plane::flipped() const {
  Plane plane = *this;
  plane.flipped_ = !flipped_;
  for (auto& c : plane.approx_) c = -c;
  return plane;
}

void Plane::compute_approx() {
  const auto e = [](double v) { return Approx::exact(v); };
  const Vec3& p = points_[0];
  const Vec3& q = points_[1];
  const Approx u[3] = {e(q[0]) - e(p[0]), e(q[1]) - e(p[1]), e(q[2]) - e(p[2])};
  Approx n[3];
  if (kind_ == Kind::kThroughPoints) {
    const Vec3& r = points_[2];
    const Approx w[3] = {e(r[0]) - e(p[0]), e(r[1]) - e(p[1]), e(r[2]) - e(p[2])};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
  } else {
    const int a = axis_, b = (a + 1) % 3, d = (a + 2) % 3;
    n[a] = Approx{};
    n[b] = u[d];
    n[d] = -u[b];
  }
  const Approx d = -(n[0] * e(p[0]) + n[1] * e(p[1]) + n[2] * e(p[2]));
  approx_ = {n[0], n[1], n[2], d};
  if (flipped_) {
    for (auto& c : approx_) c = -c;
  }
}

Eigen::Vector4d Plane::rounded() const {
  return {approx_[0].value, approx_[1].value, approx_[2].value, approx_[3].value};
}

int side_of_point(const Plane& plane, const Vec3& x) {
  // An explicit point is the meeting of the three coordinate planes through it; but the direct
  // form n . x + d is cheaper: filter, then exact.
  const auto& a = plane.approx();
  const Approx value = a[0] * Approx::exact(x[0]) + a[1] * Approx::exact(x[1]) + a[2] * Approx::exact(x[2]) + a[3];
  const int s = certain_sign(value);
  if (s != 2) return s;
  ScaledInputs scaled;
  scaled.include(plane);
  for (int k = 0; k < 3; ++k) scaled.include(x[k]);
  const auto c = ExactPlanes::coefficients(plane, scaled);
  // Coefficient k of the normal has the degree of the plane's normal in the scaled inputs and d one
  // degree more, so n . (scaled x) + d is the scaled value of n . x + d times a positive power of two.
  return sign_of(c[0] * scaled.integer(x[0]) + c[1] * scaled.integer(x[1]) + c[2] * scaled.integer(x[2]) + c[3]);
}

int normal_determinant_sign(const Plane& a, const Plane& b, const Plane& c) {
  const Approx ra[3] = {a.approx()[0], a.approx()[1], a.approx()[2]};
  const Approx rb[3] = {b.approx()[0], b.approx()[1], b.approx()[2]};
  const Approx rc[3] = {c.approx()[0], c.approx()[1], c.approx()[2]};
  const int s = certain_sign(det3(ra, rb, rc));
  if (s != 2) return s;
  ScaledInputs scaled;
  scaled.include(a);
  scaled.include(b);
  scaled.include(c);
  const auto ea = ExactPlanes::coefficients(a, scaled);
  const auto eb = ExactPlanes::coefficients(b, scaled);
  const auto ec = ExactPlanes::coefficients(c, scaled);
  return sign_of(det3(ea.data(), eb.data(), ec.data()));
}

int plane_determinant_sign(const Plane& a, const Plane& b, const Plane& c, const Plane& q) {
  const int s = certain_sign(det4(a.approx(), b.approx(), c.approx(), q.approx()));
  if (s != 2) return s;
  ScaledInputs scaled;
  scaled.include(a);
  scaled.include(b);
  scaled.include(c);
  scaled.include(q);
  return sign_of(det4(ExactPlanes::coefficients(a, scaled), ExactPlanes::coefficients(b, scaled),
                      ExactPlanes::coefficients(c, scaled), ExactPlanes::coefficients(q, scaled)));
}

int normal_component_sign(const Plane& plane, int axis) {
  const int s = certain_sign(plane.approx()[axis]);
  if (s != 2) return s;
  ScaledInputs scaled;
  scaled.include(plane);
  return sign_of(ExactPlanes::coefficients(plane, scaled)[axis]);
}

int plane_alignment(const Plane& p, const Plane& q) {
  // q's defining points lie on p, or (for a wall) its two points and the axis direction do.
  const auto& pts = q.points();
  if (side_of_point(p, pts[0]) != 0 || side_of_point(p, pts[1]) != 0) return 0;
  if (q.kind() == Plane::Kind::kThroughPoints) {
    if (side_of_point(p, pts[2]) != 0) return 0;
  } else if (normal_component_sign(p, q.axis()) != 0) {
    return 0;  // the wall contains direction e_axis, so p must too
  }
  // Same plane: compare normal directions on the largest component of p's normal.
  ScaledInputs scaled;
  scaled.include(p);
  scaled.include(q);
  const auto cp = ExactPlanes::coefficients(p, scaled);
  const auto cq = ExactPlanes::coefficients(q, scaled);
  for (int k = 0; k < 3; ++k) {
    if (sgn(cp[k]) != 0) return sgn(cp[k]) * sgn(cq[k]);
  }
  return 0;
}

bool same_plane(const Plane& p, const Plane& q) { return plane_alignment(p, q) != 0; }

namespace {

// Rows (n, d) of the three planes as Approx values.
struct ApproxRows {
  Approx n[3][3];
  Approx d[3];
  ApproxRows(const Plane& a, const Plane& b, const Plane& c) {
    const Plane* planes[3] = {&a, &b, &c};
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) n[r][k] = planes[r]->approx()[k];
      d[r] = -planes[r]->approx()[3];
    }
  }
};

// Cramer's rule for the point where three planes meet: (det N_0, det N_1, det N_2, det N), where
// N_k is the normal matrix N with column k replaced by -d. T is Approx or an exact integer type.
template <typename T>
std::array<T, 4> cramer(const T (&n)[3][3], const T (&minus_d)[3]) {
  std::array<T, 4> h;
  for (int k = 0; k < 3; ++k) {
    T m[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) m[r][col] = (col == k) ? minus_d[r] : n[r][col];
    }
    h[k] = det3(m[0], m[1], m[2]);
  }
  h[3] = det3(n[0], n[1], n[2]);
  return h;
}

}  // namespace

Homogeneous tpi_homogeneous(const Plane& a, const Plane& b, const Plane& c) {
  const ApproxRows rows(a, b, c);
  return cramer(rows.n, rows.d);
}

Homogeneous explicit_homogeneous(const Vec3& x) {
  return {Approx::exact(x[0]), Approx::exact(x[1]), Approx::exact(x[2]), Approx::exact(1)};
}

int side_of_tpi(const Plane& a, const Plane& b, const Plane& c, const Homogeneous& h, int orientation,
                const Plane& q) {
  const auto& p = q.approx();
  const int s = certain_sign(p[0] * h[0] + p[1] * h[1] + p[2] * h[2] + p[3] * h[3]);
  if (s != 2) return s * orientation;
  return plane_determinant_sign(a, b, c, q) * orientation;
}

int side_of_point(const Plane& q, const Vec3& x, const Homogeneous& h) {
  const auto& p = q.approx();
  const int s = certain_sign(p[0] * h[0] + p[1] * h[1] + p[2] * h[2] + p[3]);
  if (s != 2) return s;
  return side_of_point(q, x);
}

Vec3 tpi_coordinates(const Plane& a, const Plane& b, const Plane& c) {
  return tpi_coordinates(a, b, c, tpi_homogeneous(a, b, c));
}

bool rounded_coordinates(const Homogeneous& h, Vec3* x) {
  const double w = h[3].value;
  if (!std::isfinite(w) || !(std::abs(w) > h[3].error * kErrorSlack)) return false;
  // |x_k - X/W| <= (err_X + |x_k| err_W) / (|W| - err_W), to first order; accept it when it is tiny
  // next to the point's largest coordinate.
  const double scale = std::abs(w) - h[3].error * kErrorSlack;
  double magnitude = 0, bound = 0;
  for (int k = 0; k < 3; ++k) {
    (*x)[k] = h[k].value / w;
    magnitude = std::max(magnitude, std::abs((*x)[k]));
    bound = std::max(bound, (h[k].error + std::abs((*x)[k]) * h[3].error) * kErrorSlack / scale);
  }
  return std::isfinite(magnitude) && bound <= kCoordinateTolerance * magnitude;
}

Vec3 tpi_coordinates(const Plane& a, const Plane& b, const Plane& c, const Homogeneous& h) {
  Vec3 x;
  if (rounded_coordinates(h, &x)) return x;
  return rounded_exact(exact_tpi(exact_plane(a), exact_plane(b), exact_plane(c)));
}

ExactPlane exact_plane(const Plane& plane) {
  ScaledInputs scaled;
  scaled.include(plane);
  ExactPlane c = ExactPlanes::coefficients(plane, scaled);
  // These are the coefficients of the plane through the inputs scaled by 2^s: the normal is
  // multiplied by 2^(k s) and d by 2^((k + 1) s) (k = 2, or 1 for a wall). Multiplying the normal by
  // another 2^s (or d by 2^-s) makes them a positive multiple of the plane's own (n, d).
  if (scaled.scale >= 0) {
    for (int k = 0; k < 3; ++k) mpz_mul_2exp(c[k].get_mpz_t(), c[k].get_mpz_t(), static_cast<mp_bitcnt_t>(scaled.scale));
  } else {
    mpz_mul_2exp(c[3].get_mpz_t(), c[3].get_mpz_t(), static_cast<mp_bitcnt_t>(-scaled.scale));
  }
  return c;
}

ExactPoint exact_point(const Vec3& x) {
  ScaledInputs scaled;
  for (int k = 0; k < 3; ++k) scaled.include(x[k]);
  if (scaled.scale == std::numeric_limits<int>::min()) return {0, 0, 0, 1};  // the origin
  ExactPoint p;
  for (int k = 0; k < 3; ++k) p[k] = scaled.integer(x[k]);
  // W = 2^scale; a negative scale (huge coordinates) multiplies X, Y, Z instead.
  p[3] = 1;
  if (scaled.scale >= 0) {
    mpz_mul_2exp(p[3].get_mpz_t(), p[3].get_mpz_t(), static_cast<mp_bitcnt_t>(scaled.scale));
  } else {
    for (int k = 0; k < 3; ++k) mpz_mul_2exp(p[k].get_mpz_t(), p[k].get_mpz_t(), static_cast<mp_bitcnt_t>(-scaled.scale));
  }
  return p;
}

ExactPoint exact_tpi(const ExactPlane& a, const ExactPlane& b, const ExactPlane& c) {
  const mpz_class n[3][3] = {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}, {c[0], c[1], c[2]}};
  const mpz_class minus_d[3] = {-a[3], -b[3], -c[3]};
  ExactPoint h = cramer(n, minus_d);
  if (sgn(h[3]) < 0) {
    for (auto& v : h) v = -v;
  }
  return h;
}

int exact_side(const ExactPlane& plane, const ExactPoint& point) {
  return sgn(plane[0] * point[0] + plane[1] * point[1] + plane[2] * point[2] + plane[3] * point[3]);
}

Vec3 rounded_exact(const ExactPoint& point) {
  // X = mx 2^ex and W = mw 2^ew with mx, mw in [0.5, 1): X / W = (mx / mw) 2^(ex - ew).
  long ew = 0;
  const double mw = mpz_get_d_2exp(&ew, point[3].get_mpz_t());
  Vec3 x;
  for (int k = 0; k < 3; ++k) {
    long ex = 0;
    const double mx = mpz_get_d_2exp(&ex, point[k].get_mpz_t());
    x[k] = std::ldexp(mx / mw, static_cast<int>(ex - ew));
  }
  return x;
}

std::array<mpq_class, 3> exact_coordinates(const ExactPoint& point) {
  std::array<mpq_class, 3> x;
  for (int k = 0; k < 3; ++k) {
    x[k] = mpq_class(point[k], point[3]);
    x[k].canonicalize();  // GMP's rational functions need a positive, reduced denominator
  }
  return x;
}

int side_of_segment_meet(const Vec3& a, const Vec3& b, const Plane& p, const Plane& q) {
  const auto value = [](const Plane& plane, const Vec3& x) {
    const auto& c = plane.approx();
    return c[0] * Approx::exact(x[0]) + c[1] * Approx::exact(x[1]) + c[2] * Approx::exact(x[2]) + c[3];
  };
  const Approx pa = value(p, a), pb = value(p, b), qa = value(q, a), qb = value(q, b);
  int pb_sign = certain_sign(pb);
  const int s = certain_sign(qa * pb - pa * qb);
  if (s != 2 && pb_sign != 2) return s * pb_sign;
  // Exact: each plane value times a positive factor (the plane's and the point's own scales).
  const ExactPlane ep = exact_plane(p), eq = exact_plane(q);
  const ExactPoint ea = exact_point(a), eb = exact_point(b);
  const auto dot = [](const ExactPlane& plane, const ExactPoint& x) {
    return mpz_class(plane[0] * x[0] + plane[1] * x[1] + plane[2] * x[2] + plane[3] * x[3]);
  };
  const mpz_class Pa = dot(ep, ea), Pb = dot(ep, eb), Qa = dot(eq, ea), Qb = dot(eq, eb);
  // q(a) p(b) - p(a) q(b) = (Qa Pb - Pa Qb) / (lambda_p lambda_q W_a W_b), all factors positive.
  pb_sign = sgn(Pb);
  return sgn(mpz_class(Qa * Pb - Pa * Qb)) * pb_sign;
}

}  // namespace tetcut::geometry
