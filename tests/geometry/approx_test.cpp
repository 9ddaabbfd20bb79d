// The floating-point filter: its error bound must contain the exact value of every evaluation,
// checked against GMP rationals on random, tiny, huge and exactly degenerate inputs; and when no
// operation rounds, a zero must be certain.

#include <gtest/gtest.h>

#include <gmpxx.h>

#include <array>
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

// dot4_sign (plain products with a propagated bound first, the tracking filter when undecided):
// operands that carry errors of their own (products of inputs), against the sign of the exact
// dot product of the exact operands; nearly cancelling sums, exact zeros from grid values, and
// scales down to where the products underflow.
TEST_P(ApproxTest, Dot4SignIsTheExactSign) {
  const double scale = GetParam();
  // Products of four factors at this scale neither overflow nor underflow; grid values times a
  // power of two are exact.
  const bool in_range = std::abs(std::ilogb(scale)) <= 500;
  const bool exact_grid = in_range && scale == std::ldexp(1.0, std::ilogb(scale));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  int decided = 0;  // of the trials that do not cancel
  for (int trial = 0; trial < 3000; ++trial) {
    std::array<Approx, 4> a, b;
    mpq_class exact = 0;
    for (int k = 0; k < 4; ++k) {
      const double x = coordinate(rng) * scale, y = coordinate(rng), z = coordinate(rng) * scale, w = coordinate(rng);
      a[k] = Approx::exact(x) * Approx::exact(y);
      b[k] = Approx::exact(z) * Approx::exact(w);
      exact += mpq_class(x) * mpq_class(y) * mpq_class(z) * mpq_class(w);
    }
    if (trial % 3 == 1) {
      // Nearly cancelling: b[3] chosen in floating point to make the sum vanish, leaving only
      // rounding residue.
      const double x = a[3].value, rest = a[0].value * b[0].value + a[1].value * b[1].value + a[2].value * b[2].value;
      if (!std::isfinite(-rest / x) || x == 0) continue;  // overflowed or underflowed at this scale
      b[3] = Approx::exact(-rest / x);
      exact = mpq_class(b[3].value) * mpq_class(a[3].value);  // a[3] taken as exact too
      a[3] = Approx::exact(x);
      for (int k = 0; k < 3; ++k) {
        a[k] = Approx::exact(a[k].value);
        b[k] = Approx::exact(b[k].value);
        exact += mpq_class(a[k].value) * mpq_class(b[k].value);
      }
    }
    if (trial % 3 == 2) {
      // Exactly zero on grid values: (p, q, -p, -q) . (r, s, r, s).
      const double p = std::ldexp(std::round(coordinate(rng) * 64), -6) * scale;
      const double q = std::ldexp(std::round(coordinate(rng) * 64), -6) * scale;
      const double r = std::ldexp(std::round(coordinate(rng) * 64), -6), t = std::ldexp(std::round(coordinate(rng) * 64), -6);
      a = {Approx::exact(p), Approx::exact(q), Approx::exact(-p), Approx::exact(-q)};
      b = {Approx::exact(r), Approx::exact(t), Approx::exact(r), Approx::exact(t)};
      exact = 0;
    }
    const int s = dot4_sign(a, b);
    if (s != 2) {
      ASSERT_EQ(s, sgn(exact)) << "trial " << trial;
      if (trial % 3 != 1) ++decided;
    }
    if (trial % 3 == 2 && exact_grid) {
      EXPECT_EQ(s, 0) << "trial " << trial;  // no rounding: certain zero
    }
  }
  if (in_range) {
    EXPECT_EQ(decided, 2000);  // everything but the cancelling sums is decided
  }
}

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
