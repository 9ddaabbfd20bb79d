#include "geometry/plane.hpp"

#include <tetcut/tet_mesh.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tetcut::geometry {
namespace {

template <typename T>
T det3(const T* r0, const T* r1, const T* r2) {
  return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) - r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
         r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
}

// det of the 4x4 matrix with rows a, b, c, q, expanded along q: the cofactor sign of entry (3, j)
// is (-1)^(3 + j).
template <typename T>
T det4(const std::array<T, 4>& a, const std::array<T, 4>& b, const std::array<T, 4>& c, const std::array<T, 4>& q) {
  T result{};
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
    result = (j % 2 == 1) ? T(result + term) : T(result - term);
  }
  return result;
}

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

// A common power-of-two scale that turns a set of doubles into integers.
struct ScaledInputs {
  int scale = std::numeric_limits<int>::min();

  void include(double x) {
    if (x == 0) return;
    int exponent = 0;
    std::frexp(x, &exponent);  // x = m 2^exponent, 0.5 <= |m| < 1: x is a multiple of 2^(exponent - 53)
    scale = std::max(scale, 53 - exponent);
  }
  void include(const Vec3& x) {
    for (int k = 0; k < 3; ++k) include(x[k]);
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

void multiply_by_power_of_two(mpz_class& x, int exponent) {
  if (exponent > 0) mpz_mul_2exp(x.get_mpz_t(), x.get_mpz_t(), static_cast<mp_bitcnt_t>(exponent));
}

Approx value_at(const std::array<Approx, 4>& c, const Vec3& x) {
  return c[0] * Approx::exact(x[0]) + c[1] * Approx::exact(x[1]) + c[2] * Approx::exact(x[2]) + c[3];
}

}  // namespace

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

Plane Plane::pulled_back(const Plane& world, const std::array<Vec3, 4>& rest, const std::array<Vec3, 4>& current,
                         std::int64_t world_key) {
  Plane plane;
  plane.kind_ = Kind::kPulledBack;
  plane.pull_back_ = std::make_shared<const PullBack>(PullBack{world, rest, current, world_key});
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
  if (kind_ == Kind::kPulledBack) {
    // Q = -sum_k world(current[k]) (n_k, d_k), with (n_k, d_k) the outward rest face opposite k.
    const PullBack& b = *pull_back_;
    approx_ = {};
    for (int k = 0; k < 4; ++k) {
      const auto& f = kTetFaces[k];
      const Plane face = Plane::through(b.rest[f[0]], b.rest[f[1]], b.rest[f[2]]);
      const Approx weight = -value_at(b.world.approx(), b.current[k]);
      for (int c = 0; c < 4; ++c) approx_[c] = approx_[c] + weight * face.approx()[c];
    }
  } else {
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
  }
  if (flipped_) {
    for (auto& c : approx_) c = -c;
  }
}

bool Plane::certainly_zero() const {
  for (const Approx& c : approx_) {
    if (certain_sign(c) != 0) return false;
  }
  return true;
}

Eigen::Vector4d Plane::rounded() const {
  return {approx_[0].value, approx_[1].value, approx_[2].value, approx_[3].value};
}

ExactPlane Plane::exact() const {
  ExactPlane c;
  if (kind_ == Kind::kPulledBack) {
    // Q = -sum_k world(current[k]) (n_k, d_k) in integers. world(current[k]) times lambda W_k is
    // the integer V_k (lambda: the world plane's own factor; W_k = 2^e_k: the point's), brought to
    // the common factor W_max by shifting. The rest faces (n_k, d_k) come from the four rest
    // corners scaled by one 2^s, so they carry 2^(2s) and 2^(3s), rescaled at the end as in the
    // other kinds. Every factor is positive.
    const PullBack& b = *pull_back_;
    const ExactPlane w = b.world.exact();
    std::array<mpz_class, 4> value;
    mp_bitcnt_t largest = 0;
    std::array<mp_bitcnt_t, 4> exponent{};
    for (int k = 0; k < 4; ++k) {
      const ExactPoint x = exact_point(b.current[k]);
      value[k] = w[0] * x[0] + w[1] * x[1] + w[2] * x[2] + w[3] * x[3];
      exponent[k] = mpz_sizeinbase(x[3].get_mpz_t(), 2) - 1;  // x[3] is a power of two
      largest = std::max(largest, exponent[k]);
    }
    ScaledInputs scale;
    for (const Vec3& r : b.rest) scale.include(r);
    std::array<std::array<mpz_class, 3>, 4> r;
    for (int k = 0; k < 4; ++k) {
      for (int i = 0; i < 3; ++i) r[k][i] = scale.integer(b.rest[k][i]);
    }
    for (int i = 0; i < 4; ++i) c[i] = 0;
    for (int k = 0; k < 4; ++k) {
      multiply_by_power_of_two(value[k], static_cast<int>(largest - exponent[k]));
      const auto& f = kTetFaces[k];
      mpz_class u[3], v[3];
      for (int i = 0; i < 3; ++i) {
        u[i] = r[f[1]][i] - r[f[0]][i];
        v[i] = r[f[2]][i] - r[f[0]][i];
      }
      const mpz_class n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const mpz_class d = -(n[0] * r[f[0]][0] + n[1] * r[f[0]][1] + n[2] * r[f[0]][2]);
      for (int i = 0; i < 3; ++i) c[i] -= value[k] * n[i];
      c[3] -= value[k] * d;
    }
    if (scale.scale >= 0) {
      for (int k = 0; k < 3; ++k) multiply_by_power_of_two(c[k], scale.scale);
    } else {
      multiply_by_power_of_two(c[3], -scale.scale);
    }
  } else {
    // Integer coefficients of the plane through the inputs scaled by 2^s: the normal is multiplied
    // by 2^(k s) and d by 2^((k + 1) s) (k = 2, or 1 for a wall). Multiplying the normal by another
    // 2^s (or d by 2^-s) makes them a positive multiple of the plane's own (n, d).
    ScaledInputs s;
    s.include(points_[0]);
    s.include(points_[1]);
    if (kind_ == Kind::kThroughPoints) s.include(points_[2]);
    mpz_class p[3], u[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = s.integer(points_[0][k]);
      u[k] = s.integer(points_[1][k]) - p[k];
    }
    if (kind_ == Kind::kThroughPoints) {
      mpz_class w[3];
      for (int k = 0; k < 3; ++k) w[k] = s.integer(points_[2][k]) - p[k];
      c[0] = u[1] * w[2] - u[2] * w[1];
      c[1] = u[2] * w[0] - u[0] * w[2];
      c[2] = u[0] * w[1] - u[1] * w[0];
    } else {
      const int a = axis_, b = (a + 1) % 3, d = (a + 2) % 3;
      c[a] = 0;
      c[b] = u[d];
      c[d] = -u[b];
    }
    c[3] = -(c[0] * p[0] + c[1] * p[1] + c[2] * p[2]);
    if (s.scale >= 0) {
      for (int k = 0; k < 3; ++k) multiply_by_power_of_two(c[k], s.scale);
    } else {
      multiply_by_power_of_two(c[3], -s.scale);
    }
  }
  if (flipped_) {
    for (auto& v : c) v = -v;
  }
  return c;
}

// ---- Predicates --------------------------------------------------------------------------------

int side_of_point(const Plane& plane, const Vec3& x) { return side_of_point(plane, x, explicit_homogeneous(x)); }

int side_of_point(const Plane& q, const Vec3& x, const Homogeneous& h) {
  const auto& p = q.approx();
  const int s = dot4_sign(p, h);
  if (s != 2) return s;
  return exact_side(exact_plane(q), exact_point(x));
}

int normal_determinant_sign(const Plane& a, const Plane& b, const Plane& c) {
  const Approx ra[3] = {a.approx()[0], a.approx()[1], a.approx()[2]};
  const Approx rb[3] = {b.approx()[0], b.approx()[1], b.approx()[2]};
  const Approx rc[3] = {c.approx()[0], c.approx()[1], c.approx()[2]};
  const int s = certain_sign(det3(ra, rb, rc));
  if (s != 2) return s;
  const ExactPlane ea = exact_plane(a), eb = exact_plane(b), ec = exact_plane(c);
  return sgn(det3(ea.data(), eb.data(), ec.data()));
}

int plane_determinant_sign(const Plane& a, const Plane& b, const Plane& c, const Plane& q) {
  const int s = certain_sign(det4(a.approx(), b.approx(), c.approx(), q.approx()));
  if (s != 2) return s;
  return sgn(det4(exact_plane(a), exact_plane(b), exact_plane(c), exact_plane(q)));
}

int normal_component_sign(const Plane& plane, int axis) {
  const int s = certain_sign(plane.approx()[axis]);
  if (s != 2) return s;
  return sgn(exact_plane(plane)[axis]);
}

int wall_axis(const Plane& plane) {
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(plane.approx()[k].value) > std::abs(plane.approx()[axis].value)) axis = k;
  }
  if (normal_component_sign(plane, axis) == 0) {
    for (int k = 0; k < 3; ++k) {
      if (normal_component_sign(plane, k) != 0) axis = k;
    }
  }
  return axis;
}

int plane_alignment(const Plane& p, const Plane& q) {
  // The same plane iff the exact forms are proportional: every 2x2 minor vanishes.
  const ExactPlane ep = exact_plane(p), eq = exact_plane(q);
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      if (ep[i] * eq[j] != ep[j] * eq[i]) return 0;
    }
  }
  for (int k = 0; k < 4; ++k) {
    if (sgn(ep[k]) != 0) return sgn(ep[k]) * sgn(eq[k]);
  }
  return 0;
}

bool same_plane(const Plane& p, const Plane& q) { return plane_alignment(p, q) != 0; }

Homogeneous tpi_homogeneous(const Plane& a, const Plane& b, const Plane& c) {
  const Plane* planes[3] = {&a, &b, &c};
  Approx n[3][3], minus_d[3];
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) n[r][k] = planes[r]->approx()[k];
    minus_d[r] = -planes[r]->approx()[3];
  }
  return cramer(n, minus_d);
}

Homogeneous explicit_homogeneous(const Vec3& x) {
  return {Approx::exact(x[0]), Approx::exact(x[1]), Approx::exact(x[2]), Approx::exact(1)};
}

int side_of_tpi(const Plane& a, const Plane& b, const Plane& c, const Homogeneous& h, int orientation,
                const Plane& q) {
  const auto& p = q.approx();
  const int s = dot4_sign(p, h);
  if (s != 2) return s * orientation;
  return exact_side(exact_plane(q), exact_tpi(exact_plane(a), exact_plane(b), exact_plane(c)));
}

int side_of_segment_meet(const Vec3& a, const Vec3& b, const Plane& p, const Plane& q) {
  const Approx pa = value_at(p.approx(), a), pb = value_at(p.approx(), b);
  const Approx qa = value_at(q.approx(), a), qb = value_at(q.approx(), b);
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

// ---- Coordinates -------------------------------------------------------------------------------

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

Vec3 tpi_coordinates(const Plane& a, const Plane& b, const Plane& c) {
  return tpi_coordinates(a, b, c, tpi_homogeneous(a, b, c));
}

Vec3 tpi_coordinates(const Plane& a, const Plane& b, const Plane& c, const Homogeneous& h) {
  Vec3 x;
  if (rounded_coordinates(h, &x)) return x;
  return rounded_exact(exact_tpi(exact_plane(a), exact_plane(b), exact_plane(c)));
}

// ---- Exact forms -------------------------------------------------------------------------------

ExactPoint exact_point(const Vec3& x) {
  ScaledInputs scaled;
  scaled.include(x);
  if (scaled.scale == std::numeric_limits<int>::min()) return {0, 0, 0, 1};  // the origin
  ExactPoint p;
  for (int k = 0; k < 3; ++k) p[k] = scaled.integer(x[k]);
  // W = 2^scale; a negative scale (huge coordinates) multiplies X, Y, Z instead.
  p[3] = 1;
  if (scaled.scale >= 0) {
    multiply_by_power_of_two(p[3], scaled.scale);
  } else {
    for (int k = 0; k < 3; ++k) multiply_by_power_of_two(p[k], -scaled.scale);
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

}  // namespace tetcut::geometry
