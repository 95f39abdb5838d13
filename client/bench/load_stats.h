// Figures the load generators print: seconds of a steady_clock duration, medians and quantiles of
// their measured windows and latencies. Header-only, for the benchmarks in this folder.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace fremen::bench {

using Clock = std::chrono::steady_clock;

inline double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// The median of `v` (the upper one of an even count); 0 when empty.
inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// The q-quantile of sorted values; 0 when empty.
inline double Quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  return sorted[std::min(sorted.size() - 1, static_cast<size_t>(q * static_cast<double>(sorted.size())))];
}

}  // namespace fremen::bench
