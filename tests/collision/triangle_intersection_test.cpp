// Exact triangle-triangle intersection: analytic cases, the touching and coplanar ones, near
// misses closer than any epsilon, and agreement with a brute-force test on random triangles.

#include <tetcut/collision.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace tetcut {
namespace {

using T3 = std::array<Vec3, 3>;

T3 tri(Vec3 a, Vec3 b, Vec3 c) { return {a, b, c}; }

// Symmetric, and independent of the corners' order.
void expect_intersect(const T3& a, const T3& b, bool expected) {
  for (int r = 0; r < 3; ++r) {
    const T3 ar{a[r], a[(r + 1) % 3], a[(r + 2) % 3]}, br{b[(r + 2) % 3], b[(r + 1) % 3], b[r]};
    EXPECT_EQ(triangles_intersect(ar, br), expected) << r;
    EXPECT_EQ(triangles_intersect(br, ar), expected) << r;
  }
}

const T3 kFloor = tri({0, 0, 0}, {1, 0, 0}, {0, 1, 0});

TEST(TriangleIntersection, ApartAndCrossing) {
  expect_intersect(kFloor, tri({0, 0, 1}, {1, 0, 1}, {0, 1, 1}), false);                 // parallel, above
  expect_intersect(kFloor, tri({0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.3, 0.1, 1}), true);     // pierced
  expect_intersect(kFloor, tri({0.8, 0.8, -1}, {0.8, 0.8, 1}, {0.9, 0.7, 1}), false);    // beside the hypotenuse
  expect_intersect(kFloor, tri({-1, 0.25, -1}, {2, 0.25, -1}, {0.5, 0.25, 1}), true);    // a wall through it
}

TEST(TriangleIntersection, TouchingCounts) {
  expect_intersect(kFloor, tri({0.2, 0.2, 0}, {0.2, 0.2, 1}, {0.3, 0.1, 1}), true);      // a corner on its face
  expect_intersect(kFloor, tri({1, 0, 0}, {2, 0, 1}, {2, 1, 1}), true);                  // corner to corner
  expect_intersect(kFloor, tri({0.5, -1, 0}, {0.5, 1, 0}, {0.5, 0, 1}), true);           // an edge across, in its plane
  expect_intersect(kFloor, tri({0, 0, 0}, {1, 0, 0}, {0, 0, 1}), true);                  // sharing an edge
}

TEST(TriangleIntersection, Coplanar) {
  expect_intersect(kFloor, tri({0.1, 0.1, 0}, {0.3, 0.1, 0}, {0.1, 0.3, 0}), true);      // inside
  expect_intersect(tri({0.1, 0.1, 0}, {0.3, 0.1, 0}, {0.1, 0.3, 0}), kFloor, true);      // around
  expect_intersect(kFloor, tri({0.5, 0.5, 0}, {1, 1, 0}, {0, 1, 0}), true);              // overlapping corners
  expect_intersect(kFloor, tri({0.6, 0.6, 0}, {1, 1, 0}, {0.6, 1, 0}), false);           // beyond the hypotenuse
  expect_intersect(kFloor, tri({1, 0, 0}, {2, 0, 0}, {2, 1, 0}), true);                  // a shared corner
  expect_intersect(kFloor, tri({0.5, 0.5, 0}, {1, 1, 0}, {1, 0.5, 0}), true);            // a corner on the hypotenuse
  // In a tilted plane, where no projection is degenerate.
  const Vec3 u(1, 2, 3), v(-2, 1, 0.5), o(0.3, -0.2, 0.1);
  expect_intersect(tri(o, o + u, o + v), tri(o + 0.25 * u + 0.25 * v, o + 2 * u, o + 2 * v), true);
  expect_intersect(tri(o, o + u, o + v), tri(o + 0.75 * u + 0.75 * v, o + 2 * u, o + 2 * v), false);
}

TEST(TriangleIntersection, NearMissesAreExact) {
  const double tiny = std::ldexp(1.0, -60);
  expect_intersect(kFloor, tri({0.2, 0.2, tiny}, {0.2, 0.2, 1}, {0.3, 0.1, 1}), false);  // a corner just above
  expect_intersect(kFloor, tri({0.2, 0.2, -tiny}, {0.2, 0.2, 1}, {0.3, 0.1, 1}), true);  // just through
  // A corner beside the hypotenuse x + y = 1 by one ulp.
  const double beyond = std::nextafter(0.5, 1.0);
  expect_intersect(kFloor, tri({beyond, 0.5, 0}, {beyond, 0.5, 1}, {1, 1, 1}), false);
  expect_intersect(kFloor, tri({0.5, 0.5, 0}, {0.5, 0.5, 1}, {1, 1, 1}), true);
}

// The separating axis theorem as an independent reference: two closed triangles are disjoint
// exactly when their projections onto one of these axes are strictly apart (the normals, the
// edge-edge cross products, and the in-plane edge normals for coplanar ones). On corners with
// small integer coordinates every product here is exact in double, so the reference is exact too;
// a coarse grid makes touching and coplanar pairs frequent.
bool separated(const T3& a, const T3& b) {
  std::vector<Vec3> axes;
  const Vec3 na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
  axes.push_back(na);
  axes.push_back(nb);
  for (int i = 0; i < 3; ++i) {
    const Vec3 ea = a[(i + 1) % 3] - a[i], eb = b[(i + 1) % 3] - b[i];
    axes.push_back(na.cross(ea));
    axes.push_back(nb.cross(eb));
    for (int j = 0; j < 3; ++j) axes.push_back(ea.cross(b[(j + 1) % 3] - b[j]));
  }
  for (const Vec3& w : axes) {
    if (w.squaredNorm() == 0) continue;
    double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      amin = std::min(amin, w.dot(a[k]));
      amax = std::max(amax, w.dot(a[k]));
      bmin = std::min(bmin, w.dot(b[k]));
      bmax = std::max(bmax, w.dot(b[k]));
    }
    if (amax < bmin || bmax < amin) return true;
  }
  return false;
}

TEST(TriangleIntersection, AgreesWithSeparatingAxesOnRandomGridTriangles) {
  std::mt19937 random(7);
  std::uniform_int_distribution<int> coordinate(0, 3);
  const auto point = [&] { return Vec3(coordinate(random), coordinate(random), coordinate(random)); };
  int checked = 0, intersecting = 0, coplanar = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    T3 a{point(), point(), point()}, b{point(), point(), point()};
    if (trial % 4 == 0) {  // often in one plane z = c
      for (Vec3& p : a) p.z() = 1;
      for (Vec3& p : b) p.z() = 1;
    }
    if ((a[1] - a[0]).cross(a[2] - a[0]).squaredNorm() == 0 || (b[1] - b[0]).cross(b[2] - b[0]).squaredNorm() == 0) continue;
    ++checked;
    const bool exact = triangles_intersect(a, b);
    intersecting += exact;
    coplanar += a[0].z() == 1 && a[1].z() == 1 && a[2].z() == 1 && b[0].z() == 1 && b[1].z() == 1 && b[2].z() == 1;
    ASSERT_EQ(exact, !separated(a, b)) << "trial " << trial;
  }
  EXPECT_GT(checked, 10000);
  EXPECT_GT(intersecting, 2000);
  EXPECT_GT(coplanar, 2000);
}

}  // namespace
}  // namespace tetcut
