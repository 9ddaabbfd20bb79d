#pragma once
// A double together with a bound on its absolute error: the floating-point filter behind every
// predicate on implicit points. Each operation adds the rounding error it may commit, so after
// any polynomial evaluation |value - exact| <= error holds (up to the relative slack
// kErrorSlack, which absorbs the rounding of the error arithmetic itself).

#include <cmath>
#include <limits>

namespace tetcut::geometry {

struct Approx {
  double value = 0;
  double error = 0;

  /// An input double: exact.
  static Approx exact(double v) { return {v, 0}; }
};

// Unit roundoff doubled, so that a bound on |result| stated in terms of the rounded result stays safe.
inline constexpr double kRoundoff = std::numeric_limits<double>::epsilon();
// Underflow can lose up to the smallest normal number per product; adding it keeps the bound true
// for tiny coordinates (which then fall through to the exact path).
inline constexpr double kUnderflow = std::numeric_limits<double>::min();
// The error terms are themselves rounded (at most a few hundred operations deep, each off by at most
// one unit roundoff); 2^-40 of relative slack covers that with a wide margin.
inline constexpr double kErrorSlack = 1.0 + 0x1p-40;

inline Approx operator+(Approx a, Approx b) {
  const double v = a.value + b.value;
  return {v, a.error + b.error + kRoundoff * std::abs(v)};
}
inline Approx operator-(Approx a, Approx b) {
  const double v = a.value - b.value;
  return {v, a.error + b.error + kRoundoff * std::abs(v)};
}
inline Approx operator-(Approx a) { return {-a.value, a.error}; }
inline Approx operator*(Approx a, Approx b) {
  const double v = a.value * b.value;
  return {v, std::abs(a.value) * b.error + std::abs(b.value) * a.error + a.error * b.error +
                 kRoundoff * std::abs(v) + kUnderflow};
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

}  // namespace tetcut::geometry
