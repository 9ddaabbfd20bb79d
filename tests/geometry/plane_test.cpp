// Plane predicates: checked against an independent exact evaluation in rational arithmetic, on
// random, nearly degenerate and exactly degenerate configurations.

#include <gtest/gtest.h>

#include <gmpxx.h>

#include <cmath>
#include <random>

#include "geometry/plane.hpp"
#include "geometry/predicates.hpp"

namespace tetcut::geometry {
namespace {

using Q3 = std::array<mpq_class, 3>;

// Reference: exact plane (n, d) over the rationals, from the definition.
std::array<mpq_class, 4> reference_plane(const Plane& plane) {
  const auto& pts = plane.points();
  Q3 p, u;
  for (int k = 0; k < 3; ++k) {
    p[k] = pts[0][k];
    u[k] = mpq_class(pts[1][k]) - p[k];
  }
  Q3 n;
  if (plane.kind() == Plane::Kind::kThroughPoints) {
    Q3 w;
    for (int k = 0; k < 3; ++k) w[k] = mpq_class(pts[2][k]) - p[k];
    n = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  } else {
    Q3 e = {0, 0, 0};
    e[plane.axis()] = 1;
    n = {u[1] * e[2] - u[2] * e[1], u[2] * e[0] - u[0] * e[2], u[0] * e[1] - u[1] * e[0]};
  }
  // Orientation: a flipped plane has the opposite sign of its rounded approximation.
  const mpq_class d = -(n[0] * p[0] + n[1] * p[1] + n[2] * p[2]);
  std::array<mpq_class, 4> c = {n[0], n[1], n[2], d};
  int largest = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(plane.approx()[k].value) > std::abs(plane.approx()[largest].value)) largest = k;
  }
  if ((plane.approx()[largest].value < 0) != (c[largest] < 0)) {
    for (auto& v : c) v = -v;
  }
  return c;
}

// Reference: the exact point where three planes meet, by Cramer's rule over the rationals.
std::array<mpq_class, 3> reference_point(const Plane& a, const Plane& b, const Plane& c) {
  const auto pa = reference_plane(a), pb = reference_plane(b), pc = reference_plane(c);
  const auto det3 = [](const Q3& r0, const Q3& r1, const Q3& r2) -> mpq_class {
    return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) - r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
           r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
  };
  const Q3 rows[3] = {{pa[0], pa[1], pa[2]}, {pb[0], pb[1], pb[2]}, {pc[0], pc[1], pc[2]}};
  const Q3 rhs = {-pa[3], -pb[3], -pc[3]};
  const mpq_class det = det3(rows[0], rows[1], rows[2]);
  std::array<mpq_class, 3> x;
  for (int k = 0; k < 3; ++k) {
    Q3 m[3] = {rows[0], rows[1], rows[2]};
    for (int r = 0; r < 3; ++r) m[r][k] = rhs[r];
    x[k] = det3(m[0], m[1], m[2]) / det;
  }
  return x;
}

// Reference: the exact point where three planes meet, and the side of q there.
int reference_side(const Plane& a, const Plane& b, const Plane& c, const Plane& q) {
  const auto pa = reference_plane(a), pb = reference_plane(b), pc = reference_plane(c), pq = reference_plane(q);
  const auto det3 = [](const Q3& r0, const Q3& r1, const Q3& r2) -> mpq_class {
    return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) - r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
           r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
  };
  const Q3 n[3] = {{pa[0], pa[1], pa[2]}, {pb[0], pb[1], pb[2]}, {pc[0], pc[1], pc[2]}};
  const Q3 rhs = {-pa[3], -pb[3], -pc[3]};
  const mpq_class det = det3(n[0], n[1], n[2]);
  mpq_class value = pq[3];
  for (int k = 0; k < 3; ++k) {
    Q3 m[3] = {n[0], n[1], n[2]};
    for (int r = 0; r < 3; ++r) m[r][k] = rhs[r];
    value += pq[k] * det3(m[0], m[1], m[2]) / det;
  }
  return sgn(value);
}

class PlaneTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng{20261122};
  Vec3 random_point(double scale = 1) {
    std::uniform_real_distribution<double> coord(-scale, scale);
    return {coord(rng), coord(rng), coord(rng)};
  }
  Plane random_plane() {
    if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) {
      return Plane::wall(random_point(), random_point(), std::uniform_int_distribution<int>(0, 2)(rng));
    }
    return Plane::through(random_point(), random_point(), random_point());
  }
};

TEST_F(PlaneTest, SideOfInputPointMatchesOrient3d) {
  for (int trial = 0; trial < 5000; ++trial) {
    const Vec3 p = random_point(), q = random_point(), r = random_point();
    // x nearly on the plane, so the filter often cannot decide.
    const Vec3 x = p + 0.3 * (q - p) + 0.9 * (r - p);
    ASSERT_EQ(side_of_point(Plane::through(p, q, r), x), orient3d(p, q, r, x));
  }
}

TEST_F(PlaneTest, WallSideIsTheProjectedOrientation) {
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 p = random_point(), q = random_point(), x = random_point();
    const int axis = trial % 3, u = (axis + 1) % 3, v = (axis + 2) % 3;
    // n = (q - p) x e_axis, so n . (x - p) = orient2d of (p, q, x) projected onto (u, v), negated.
    const double pp[2] = {p[u], p[v]}, qq[2] = {q[u], q[v]}, xx[2] = {x[u], x[v]};
    ASSERT_EQ(side_of_point(Plane::wall(p, q, axis), x), -orient2d(pp, qq, xx));
  }
}

TEST_F(PlaneTest, TpiSideMatchesRationalReference) {
  int zeros = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Plane a = random_plane(), b = random_plane(), c = random_plane();
    const int orientation = normal_determinant_sign(a, b, c);
    if (orientation == 0) continue;
    Plane q;
    switch (trial % 3) {
      case 0:  // generic
        q = random_plane();
        break;
      case 1: {  // through the rounded meeting point: the exact side is tiny, often zero
        const Vec3 x = tpi_coordinates(a, b, c);
        q = Plane::through(x, random_point(), random_point());
        break;
      }
      default:  // one of the defining planes, flipped: exactly zero
        q = b.flipped();
        break;
    }
    const int side = side_of_tpi(a, b, c, orientation, q);
    ASSERT_EQ(side, reference_side(a, b, c, q)) << "trial " << trial;
    zeros += side == 0;
  }
  EXPECT_GT(zeros, 900);
}

TEST_F(PlaneTest, PlanesThroughACommonInputPointMeetThere) {
  // Four planes through one input vertex: the fourth passes exactly through the meeting point of
  // the other three, whatever rounding the coefficients suffer.
  for (int trial = 0; trial < 1000; ++trial) {
    const Vec3 o = random_point(1e3);
    const Plane a = Plane::through(o, random_point(), random_point());
    const Plane b = Plane::through(random_point(), o, random_point());
    const Plane c = Plane::wall(o, random_point(), trial % 3);
    const Plane q = Plane::through(random_point(), random_point(), o);
    const int orientation = normal_determinant_sign(a, b, c);
    if (orientation == 0) continue;
    ASSERT_EQ(side_of_tpi(a, b, c, orientation, q), 0);
  }
}

TEST_F(PlaneTest, SamePlaneFromDifferentDefinitions) {
  const Vec3 p(0.1, 0.2, 0.3), q(0.7, 0.2, 0.3), r(0.1, 0.9, 0.3);
  const Plane horizontal = Plane::through(p, q, r);
  // Another triple of points of z = 0.3.
  EXPECT_EQ(plane_alignment(horizontal, Plane::through(Vec3(5, 5, 0.3), Vec3(-3, 1, 0.3), Vec3(2, -7, 0.3))), 1);
  EXPECT_EQ(plane_alignment(horizontal, Plane::through(Vec3(5, 5, 0.3), Vec3(2, -7, 0.3), Vec3(-3, 1, 0.3))), -1);
  EXPECT_EQ(plane_alignment(horizontal, Plane::through(q, r, p)), 1);
  EXPECT_EQ(plane_alignment(horizontal, horizontal.flipped()), -1);
  // A wall through two points of z = 0.3 along z is not that plane, but along x it is.
  EXPECT_EQ(plane_alignment(horizontal, Plane::wall(p, r, 2)), 0);
  EXPECT_EQ(plane_alignment(horizontal, Plane::wall(p, r, 0)), -1);
  // ...but the wall along z through (0.1, 0.2) and (0.7, 0.2) is the plane y = 0.2.
  const Plane y_plane = Plane::through(Vec3(0, 0.2, 0), Vec3(0, 0.2, 1), Vec3(1, 0.2, 0));
  EXPECT_NE(plane_alignment(y_plane, Plane::wall(p, q, 2)), 0);
  EXPECT_NE(plane_alignment(Plane::wall(p, q, 2), y_plane), 0);
  EXPECT_FALSE(same_plane(y_plane, horizontal));
}

TEST_F(PlaneTest, TinyAndHugeCoordinatesFallBackToExact) {
  for (const double scale : {std::ldexp(1.0, -680), std::ldexp(1.0, 680)}) {
    // Powers of two scale exactly; the products of the scaled coordinates underflow or overflow.
    const Vec3 p0(1, 2, 3), q0(4, -1, 2), r0(0, 5, -2);
    const Plane plane = Plane::through(p0 * scale, q0 * scale, r0 * scale);
    EXPECT_EQ(side_of_point(plane, p0 * scale), 0);
    EXPECT_EQ(side_of_point(plane, (q0 + 0.25 * (r0 - q0)) * scale), 0);
    const Vec3 normal = (q0 - p0).cross(r0 - p0);
    EXPECT_EQ(side_of_point(plane, (p0 + normal * 1e-3) * scale), 1);
    EXPECT_EQ(side_of_point(plane, (p0 - normal * 1e-3) * scale), -1);
  }
}

// The cached exact forms: each plane's integers are a positive multiple of its (n, d), and points
// from exact_tpi are the reference points, for planes whose inputs have very different scales.
TEST_F(PlaneTest, ExactFormsAreScaledCopies) {
  std::mt19937_64 generator(11);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int trial = 0; trial < 300; ++trial) {
    // Scales differ per plane, so each is turned into integers with its own power of two.
    const auto random_point = [&](double scale) -> Vec3 {
      return Vec3(unit(generator), unit(generator), unit(generator)) * scale;
    };
    const double scales[3] = {1.0 / 1024, 1.0, 4096.0};
    Plane planes[3];
    for (int i = 0; i < 3; ++i) {
      const double s = scales[(trial + i) % 3];
      planes[i] = (trial + i) % 4 == 0 ? Plane::wall(random_point(s), random_point(s), i)
                                       : Plane::through(random_point(s), random_point(s), random_point(s));
    }
    for (const Plane& plane : planes) {
      const ExactPlane e = exact_plane(plane);
      const auto r = reference_plane(plane);
      // e = lambda * r with lambda > 0: compare through the largest reference component.
      int k = 0;
      for (int j = 1; j < 4; ++j) {
        if (abs(r[j]) > abs(r[k])) k = j;
      }
      const mpq_class lambda = mpq_class(e[k]) / r[k];
      ASSERT_GT(lambda, 0);
      for (int j = 0; j < 4; ++j) ASSERT_EQ(mpq_class(e[j]), lambda * r[j]);
    }
    if (normal_determinant_sign(planes[0], planes[1], planes[2]) == 0) continue;
    const ExactPoint point = exact_tpi(exact_plane(planes[0]), exact_plane(planes[1]), exact_plane(planes[2]));
    ASSERT_GT(point[3], 0);
    const auto x = exact_coordinates(point);
    const auto reference = reference_point(planes[0], planes[1], planes[2]);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(x[k], reference[k]);
    const Plane q = Plane::through(random_point(1), random_point(1), random_point(1));
    ASSERT_EQ(exact_side(exact_plane(q), point), reference_side(planes[0], planes[1], planes[2], q));
  }
}

// Pulled-back planes: Q(X) has the sign of world(phi(X)) for the affine map phi from the rest
// corners to the current ones, computed here independently in rationals.
struct Deformed {
  std::array<Vec3, 4> rest, current;
};

// The world point phi(X) for rest point X, exactly.
Q3 deform(const Deformed& t, const Q3& x) {
  // Barycentric coordinates of X: solve [r1 - r0, r2 - r0, r3 - r0] w = X - r0 by Cramer's rule.
  Q3 e[3], rhs;
  for (int k = 0; k < 3; ++k) rhs[k] = x[k] - t.rest[0][k];
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 3; ++k) e[c][k] = mpq_class(t.rest[c + 1][k]) - t.rest[0][k];
  }
  // Columns e[c]: det of the matrix with rows k = (e0[k], e1[k], e2[k]).
  const auto det_columns = [](const Q3& a, const Q3& b, const Q3& c) -> mpq_class {
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1]) + c[0] * (a[1] * b[2] - a[2] * b[1]);
  };
  const mpq_class det = det_columns(e[0], e[1], e[2]);
  const mpq_class w1 = det_columns(rhs, e[1], e[2]) / det, w2 = det_columns(e[0], rhs, e[2]) / det,
                  w3 = det_columns(e[0], e[1], rhs) / det;
  const mpq_class w0 = 1 - w1 - w2 - w3;
  Q3 y;
  for (int k = 0; k < 3; ++k) {
    y[k] = w0 * t.current[0][k] + w1 * t.current[1][k] + w2 * t.current[2][k] + w3 * t.current[3][k];
  }
  return y;
}

int world_side(const Plane& world, const Q3& y) {
  const auto c = reference_plane(world);
  return sgn(c[0] * y[0] + c[1] * y[1] + c[2] * y[2] + c[3]);
}

Deformed random_deformed(std::mt19937_64& generator) {
  std::uniform_real_distribution<double> unit(-1, 1);
  Deformed t;
  do {
    for (Vec3& p : t.rest) p = Vec3(unit(generator), unit(generator), unit(generator));
  } while (orient3d(t.rest[0], t.rest[1], t.rest[2], t.rest[3]) <= 0);
  for (int k = 0; k < 4; ++k) t.current[k] = t.rest[k] + 0.5 * Vec3(unit(generator), unit(generator), unit(generator));
  return t;
}

TEST_F(PlaneTest, PulledBackPlaneHasTheSignOfTheWorldPlaneAtTheDeformedPoint) {
  std::mt19937_64 generator(21);
  std::uniform_real_distribution<double> unit(-1, 1);
  const auto point = [&]() -> Vec3 { return Vec3(unit(generator), unit(generator), unit(generator)); };
  for (int trial = 0; trial < 200; ++trial) {
    const Deformed t = random_deformed(generator);
    const Plane world = trial % 3 == 0 ? Plane::wall(point(), point(), trial % 3) : Plane::through(point(), point(), point());
    const Plane pulled = Plane::pulled_back(world, t.rest, t.current);
    for (int sample = 0; sample < 10; ++sample) {
      const Vec3 x = point();
      ASSERT_EQ(side_of_point(pulled, x), world_side(world, deform(t, {mpq_class(x[0]), mpq_class(x[1]), mpq_class(x[2])})));
    }
    // The rest corners map to the current corners: the pulled-back plane's sign there is the
    // world plane's sign at the current corner, exactly, even when that is zero.
    for (int k = 0; k < 4; ++k) ASSERT_EQ(side_of_point(pulled, t.rest[k]), side_of_point(world, t.current[k]));
    // A world plane through two current corners pulls back to a plane through the rest corners.
    const Plane through_corners = Plane::through(t.current[0], t.current[1], point());
    const Plane back = Plane::pulled_back(through_corners, t.rest, t.current);
    ASSERT_EQ(side_of_point(back, t.rest[0]), 0);
    ASSERT_EQ(side_of_point(back, t.rest[1]), 0);
  }
}

// The exact form of a pulled-back plane, evaluated anywhere, is one positive multiple of
// world(phi(X)), computed independently in rationals.
TEST_F(PlaneTest, PulledBackExactFormIsAPositiveMultipleOfTheReference) {
  std::mt19937_64 generator(23);
  std::uniform_real_distribution<double> unit(-1, 1);
  const auto point = [&]() -> Vec3 { return Vec3(unit(generator), unit(generator), unit(generator)); };
  for (int trial = 0; trial < 100; ++trial) {
    Deformed t = random_deformed(generator);
    // Corners of very different magnitudes, so the points' own scales differ.
    t.current[1] *= 1024;
    t.current[2] /= 512;
    const Plane world = trial % 2 ? Plane::wall(point(), point(), 1) : Plane::through(point(), point(), point());
    const ExactPlane e = Plane::pulled_back(world, t.rest, t.current).exact();
    mpq_class ratio = 0;
    for (int sample = 0; sample < 6; ++sample) {
      const Vec3 x = point();
      const Q3 q = {mpq_class(x[0]), mpq_class(x[1]), mpq_class(x[2])};
      const Q3 y = deform(t, q);
      const auto c = reference_plane(world);
      const mpq_class reference = c[0] * y[0] + c[1] * y[1] + c[2] * y[2] + c[3];
      const mpq_class value = e[0] * q[0] + e[1] * q[1] + e[2] * q[2] + e[3];
      if (reference == 0) {
        ASSERT_EQ(value, 0);
        continue;
      }
      const mpq_class r = value / reference;
      ASSERT_GT(r, 0) << trial;
      if (ratio == 0) ratio = r;
      ASSERT_EQ(r, ratio) << trial;
    }
  }
}

TEST_F(PlaneTest, TetsSharingAFaceAgreeOnItExactly) {
  std::mt19937_64 generator(22);
  std::uniform_real_distribution<double> unit(-1, 1);
  const auto point = [&]() -> Vec3 { return Vec3(unit(generator), unit(generator), unit(generator)); };
  for (int trial = 0; trial < 200; ++trial) {
    // Tets A = (r0, r1, r2, r3) and B = (r0, r2, r1, s) share face (r0, r1, r2) and its current
    // corners; their fourth corners and their motions differ.
    Deformed a = random_deformed(generator);
    Deformed b;
    b.rest = {a.rest[0], a.rest[2], a.rest[1], Vec3::Zero()};
    b.current = {a.current[0], a.current[2], a.current[1], Vec3::Zero()};
    do {
      b.rest[3] = point();
    } while (orient3d(b.rest[0], b.rest[1], b.rest[2], b.rest[3]) <= 0);
    b.current[3] = b.rest[3] + 0.5 * point();
    const Plane world = Plane::through(point(), point(), point());
    const Plane qa = Plane::pulled_back(world, a.rest, a.current), qb = Plane::pulled_back(world, b.rest, b.current);
    // Where qa meets the shared face, along any third plane, qb passes too.
    const Plane face = Plane::through(a.rest[0], a.rest[1], a.rest[2]);
    const Plane across = Plane::through(point(), point(), point());
    if (normal_determinant_sign(face, qa, across) == 0) continue;
    const Homogeneous h = tpi_homogeneous(face, qa, across);
    ASSERT_EQ(side_of_tpi(face, qa, across, h, normal_determinant_sign(face, qa, across), qb), 0) << trial;
  }
}

}  // namespace
}  // namespace tetcut::geometry
