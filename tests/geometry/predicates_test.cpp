// orient3d / orient2d: the filtered result must always equal the exact one, including on inputs
// built to be coplanar or within a rounding error of it.

#include <gtest/gtest.h>

#include <random>

#include "geometry/predicates.hpp"

namespace tetcut::geometry {
namespace {

TEST(Orient3d, SignsOfTheUnitTet) {
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  EXPECT_EQ(orient3d(o, x, y, z), 1);
  EXPECT_EQ(orient3d(o, y, x, z), -1);
  EXPECT_EQ(orient3d(o, x, y, Vec3(0.3, 0.7, 0)), 0);
}

TEST(Orient3d, FilterAgreesWithExactOnNearlyCoplanarPoints) {
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> coord(-10, 10);
  std::uniform_real_distribution<double> weight(-2, 3);
  int zeros = 0, undecidable_in_double = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 a(coord(rng), coord(rng), coord(rng)), b(coord(rng), coord(rng), coord(rng)),
        c(coord(rng), coord(rng), coord(rng));
    // d on the plane abc up to rounding: exact sign is usually non-zero but tiny.
    const double s = weight(rng), t = weight(rng);
    const Vec3 d = a + s * (b - a) + t * (c - a);
    const int filtered = orient3d(a, b, c, d);
    ASSERT_EQ(filtered, orient3d_exact(a.data(), b.data(), c.data(), d.data())) << "trial " << trial;
    zeros += filtered == 0;
    const double naive = (b - a).cross(c - a).dot(d - a);
    undecidable_in_double += (naive > 0 ? 1 : naive < 0 ? -1 : 0) != filtered;
  }
  // The test is only meaningful if plain doubles get some of these wrong.
  EXPECT_GT(undecidable_in_double, 100);
  (void)zeros;
}

TEST(Orient3d, ExactlyCoplanarIntegerGridPoints) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-1000, 1000);
  for (int trial = 0; trial < 2000; ++trial) {
    // Points on the plane x + 2y - 3z = 5 with huge offsets that round in double.
    auto on_plane = [&]() -> Vec3 {
      const double y = coord(rng), z = coord(rng);
      return Vec3(5 - 2 * y + 3 * z, y, z) * 1e15;
    };
    EXPECT_EQ(orient3d(on_plane(), on_plane(), on_plane(), on_plane()), 0);
  }
}

TEST(Orient2d, CollinearAndNot) {
  EXPECT_TRUE(collinear(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(3, 3, 3)));
  EXPECT_TRUE(collinear(Vec3(0.1, 0.2, 0.3), Vec3(0.1, 0.2, 0.3), Vec3(5, 6, 7)));
  EXPECT_FALSE(collinear(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(3, 3, 3.0000000000000004)));
  const double a[2] = {0, 0}, b[2] = {1, 0}, c[2] = {0, 1};
  EXPECT_EQ(orient2d(a, b, c), 1);
  EXPECT_EQ(orient2d(a, c, b), -1);
}

}  // namespace
}  // namespace tetcut::geometry
