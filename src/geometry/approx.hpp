#pragma once
// A double together with a bound on its absolute error: the floating-point filter behind every
// predicate on implicit points. Each operation adds the rounding error it actually committed,
// computed exactly by an error-free transformation (Knuth's TwoSum, Dekker's TwoProduct), so after
// any polynomial evaluation |value - exact| <= error (up to the relative slack kErrorSlack, which
// absorbs the rounding of the error arithmetic itself).
//
// Tracking the actual error rather than a bound like eps * |value| matters for degenerate input:
// when every operation is exact (grid-aligned coordinates, points exactly on planes), the error
// stays exactly zero and a zero result is certain, so the exact GMP path is not needed.

#include <array>
#include <cmath>
#include <limits>

namespace tetcut::geometry {

struct Approx {
  double value = 0;
  double error = 0;

  /// An input double: exact.
  static Approx exact(double v) { return {v, 0}; }
};

// The error terms are themselves rounded (at most a few hundred operations deep, each off by at most
// one unit roundoff); 2^-40 of relative slack covers that with a wide margin.
inline constexpr double kErrorSlack = 1.0 + 0x1p-40;
// Below this magnitude a product may underflow, and Dekker's error term is no longer exact; the
// smallest normal number bounds what can be lost there.
inline constexpr double kUnderflowRisk = 0x1p-960;
inline constexpr double kUnderflow = std::numeric_limits<double>::min();

namespace detail {

// Rounding error of s = a + b, exactly (Knuth's TwoSum; no overflow assumed: a non-finite sum is
// caught by certain_sign).
inline double two_sum_error(double a, double b, double s) {
  const double bb = s - a;
  return (a - (s - bb)) + (b - bb);
}

// Rounding error of p = a * b, exactly, by Dekker's splitting (no FMA needed).
inline double two_product_error(double a, double b, double p) {
  constexpr double kSplitter = 134217729.0;  // 2^27 + 1
  const double ca = kSplitter * a, a_hi = ca - (ca - a), a_lo = a - a_hi;
  const double cb = kSplitter * b, b_hi = cb - (cb - b), b_lo = b - b_hi;
  return ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo;
}

}  // namespace detail

inline Approx operator+(Approx a, Approx b) {
  const double v = a.value + b.value;
  return {v, a.error + b.error + std::abs(detail::two_sum_error(a.value, b.value, v))};
}
inline Approx operator-(Approx a) { return {-a.value, a.error}; }
inline Approx operator-(Approx a, Approx b) { return a + (-b); }
inline Approx operator*(Approx a, Approx b) {
  const double v = a.value * b.value;
  double error = std::abs(a.value) * b.error + std::abs(b.value) * a.error + a.error * b.error;
  // The propagated error may itself underflow; each product then loses less than the smallest
  // normal number.
  if ((a.error > 0 || b.error > 0) && error < kUnderflowRisk) error += kUnderflow;
  if (std::abs(v) < kUnderflowRisk && a.value != 0 && b.value != 0) {
    error += kUnderflow;  // Dekker's error term is not exact near underflow
  } else {
    error += std::abs(detail::two_product_error(a.value, b.value, v));
  }
  return {v, error};
}

/// The sign of the exact value when the bound decides it, or 2 ("unknown") when it does not,
/// including when anything overflowed.
inline int certain_sign(Approx a) {
  if (!std::isfinite(a.value) || !std::isfinite(a.error)) return 2;
  const double bound = a.error * kErrorSlack;
  if (a.value > bound) return 1;
  if (-a.value > bound) return -1;
  if (a.value == 0 && a.error == 0) return 0;
  return 2;
}

/// certain_sign(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]), the commonest predicate (a
/// plane at a homogeneous point), deciding most cases with a cheaper bound first: plain products
/// and sums, off from the exact value by at most the propagated input errors plus 8 units of
/// roundoff times the sum of the products' magnitudes (a dot product of 4 terms rounds at most 4
/// times; 8 leaves room for the rounding of the bound itself). Tiny results, where underflow could
/// break that bound, and undecided ones go to the error-tracking evaluation, which also certifies
/// exact zeros.
namespace detail {
// The error-tracking evaluation, out of line so that dot4_sign's fast path inlines.
[[gnu::noinline]] inline int dot4_sign_tracked(const std::array<Approx, 4>& a, const std::array<Approx, 4>& b) {
  return certain_sign(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
}
}  // namespace detail

[[gnu::always_inline]] inline int dot4_sign(const std::array<Approx, 4>& a, const std::array<Approx, 4>& b) {
  double value = 0, magnitude = 0, error = 0;
  for (int k = 0; k < 4; ++k) {
    const double product = a[k].value * b[k].value;
    value += product;
    magnitude += std::abs(product);
    error += std::abs(a[k].value) * b[k].error + std::abs(b[k].value) * a[k].error + a[k].error * b[k].error;
  }
  constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;
  constexpr double kTiny = 0x1p-900;  // far above anything underflow can lose
  const double bound = (error + 8 * kUnit * magnitude) * kErrorSlack + kTiny;
  if (value > bound) return 1;   // false for NaN, which falls through
  if (-value > bound) return -1;
  return detail::dot4_sign_tracked(a, b);
}

}  // namespace tetcut::geometry
