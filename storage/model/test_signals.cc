#include "storage/model/test_signals.h"

#include <algorithm>

namespace fremen::model::testing {

std::vector<double> RandomTimes(size_t n, double t0, double span, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, span);
  std::vector<double> times(n);
  for (double& t : times) t = t0 + u(rng);
  std::sort(times.begin(), times.end());
  return times;
}

std::vector<double> UniformTimes(size_t n, double t0, double step) {
  std::vector<double> times(n);
  for (size_t i = 0; i < n; ++i) times[i] = t0 + step * static_cast<double>(i);
  return times;
}

std::vector<Observation> Sample(const std::vector<double>& times, const std::function<float(double)>& f) {
  std::vector<Observation> out;
  out.reserve(times.size());
  for (double t : times) out.push_back({t, f(t)});
  return out;
}

std::vector<Observation> SampleBernoulli(const std::vector<double>& times, const std::function<double(double)>& f,
                                         uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Observation> out;
  out.reserve(times.size());
  for (double t : times) out.push_back({t, u(rng) < f(t) ? 1.0f : 0.0f});
  return out;
}

}  // namespace fremen::model::testing
