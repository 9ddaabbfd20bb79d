// The floating-point filter: its error bound must contain the exact value of every evaluation,
// checked against GMP rationals on random, tiny, huge and exactly degenerate inputs; and when no
// operation rounds, a zero must be certain.

#include <gtest/gtest.h>

#include <gmpxx.h>

#include <cmath>
#include <random>

#include "geometry/approx.hpp"

namespace tetcut::geometry {
namespace {

template <typename T>
T det3(const T (&m)[3][3]) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// |approx.value - exact| <= approx.error * kErrorSlack, in exact arithmetic.
bool bound_holds(const Approx& a, const mpq_class& exact) {
  if (!std::isfinite(a.value) || !std::isfinite(a.error)) return true;  // certain_sign gives up then
  const mpq_class difference = abs(mpq_class(a.value) - exact);
  return difference <= mpq_class(a.error) * mpq_class(kErrorSlack);
}

class ApproxTest : public ::testing::TestWithParam<double> {};

TEST_P(ApproxTest, BoundContainsTheExactDeterminant) {
  const double scale = GetParam();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    Approx a[3][3];
    mpq_class q[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const double x = coordinate(rng) * scale;
        a[r][c] = Approx::exact(x);
        q[r][c] = x;
      }
    }
    if (trial % 3 == 0) {
      // Exactly singular in the inputs: row 2 = row 0 + row 1 where the sums are exact (halves of
      // small integers), so the determinant is exactly zero.
      for (int c = 0; c < 3; ++c) {
        const double x = std::ldexp(std::round(coordinate(rng) * 64), -6) * scale;
        const double y = std::ldexp(std::round(coordinate(rng) * 64), -6) * scale;
        a[0][c] = Approx::exact(x);
        a[1][c] = Approx::exact(y);
        a[2][c] = Approx::exact(x + y);
        q[0][c] = x;
        q[1][c] = y;
        q[2][c] = x + y;
      }
    }
    const Approx value = det3(a);
    const mpq_class exact = det3(q);
    ASSERT_TRUE(bound_holds(value, exact)) << "trial " << trial;
    const int s = certain_sign(value);
    if (s != 2) {
      ASSERT_EQ(s, sgn(exact)) << "trial " << trial;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Scales, ApproxTest, ::testing::Values(1.0, 1e-200, 1e200, std::ldexp(1.0, -500), 0x1p-1000));

TEST(Approx, ExactOperationsCertifyZero) {
  // (0.5 * 3 - 1.25) * 4 - 1 = 0, every step exact.
  const Approx x = (Approx::exact(0.5) * Approx::exact(3) - Approx::exact(1.25)) * Approx::exact(4) - Approx::exact(1);
  EXPECT_EQ(x.error, 0);
  EXPECT_EQ(certain_sign(x), 0);
  // 0.1 * 3 - 0.3 rounds on the way: the filter must not claim certainty about its sign.
  const Approx y = Approx::exact(0.1) * Approx::exact(3) - Approx::exact(0.3);
  EXPECT_GT(y.error, 0);
  EXPECT_TRUE(bound_holds(y, mpq_class(0.1) * 3 - mpq_class(0.3)));
}

TEST(Approx, OverflowIsNeverCertain) {
  const Approx big = Approx::exact(1e200) * Approx::exact(1e200);
  EXPECT_EQ(certain_sign(big), 2);
}

}  // namespace
}  // namespace tetcut::geometry
