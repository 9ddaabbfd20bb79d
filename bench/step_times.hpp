#pragma once
// What the plain benchmark programs (sim, live) share: wall time in milliseconds since a moment,
// and percentiles of consecutive steps' times.

#include <algorithm>
#include <chrono>
#include <vector>

namespace tetcut::bench {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point start) { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); }

/// The value at fraction p (0 .. 1) of the sorted values, nearest rank; 0 for none.
inline double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}
inline double median(const std::vector<double>& v) { return percentile(v, 0.5); }
inline double mean(const std::vector<double>& v) {
  double sum = 0;
  for (const double x : v) sum += x;
  return v.empty() ? 0 : sum / static_cast<double>(v.size());
}

}  // namespace tetcut::bench
