// Generated observation series for the model tests: known periodic signals, random irregular
// sampling, noise. Deterministic for a given seed.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "storage/model/observation.h"

namespace fremen::model::testing {

// n times drawn uniformly from [t0, t0 + span), sorted.
std::vector<double> RandomTimes(size_t n, double t0, double span, uint64_t seed);
// n times t0, t0 + step, ...
std::vector<double> UniformTimes(size_t n, double t0, double step);

// s(t) = f(t) at each time.
std::vector<Observation> Sample(const std::vector<double>& times, const std::function<float(double)>& f);
// s(t) = 1 with probability f(t), else 0.
std::vector<Observation> SampleBernoulli(const std::vector<double>& times, const std::function<double(double)>& f,
                                         uint64_t seed);

}  // namespace fremen::model::testing
