#include "storage/model/kernels/kernel_test_data.h"

#include <cmath>

#include "storage/model/test_signals.h"

namespace fremen::model::testing {

CompactSpectrum RandomCellSpectrum(const PeriodSet& periods, std::mt19937_64& rng, int max_observations) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = std::uniform_int_distribution<int>(0, max_observations)(rng);
  const double span = u(rng) * 3 * kWeekSeconds;
  const double mean = u(rng), daily = 0.4 * u(rng), weekly = 0.3 * u(rng), phase = 6.28 * u(rng);
  const auto obs = SampleBernoulli(
      RandomTimes(n, 1.7e9, span, rng()),
      [&](double t) {
        return mean + daily * std::cos(ReducedPhase(t, 86400) + phase) +
               weekly * std::cos(ReducedPhase(t, kWeekSeconds));
      },
      rng());
  CompactSpectrum spectrum(periods.size());
  spectrum.AddBatch(obs, periods);
  return spectrum;
}

std::vector<CompactSpectrum> RandomCellSpectra(const PeriodSet& periods, size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<CompactSpectrum> spectra;
  spectra.reserve(count);
  for (size_t i = 0; i < count; ++i) spectra.push_back(RandomCellSpectrum(periods, rng));
  return spectra;
}

OrderErrors RandomOrderErrors(int max_order, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> errors(max_order + 1);
  for (double& e : errors) e = 10 * u(rng);
  OrderErrors result(max_order);
  result.Restore(1.7e9, 10 + u(rng), std::move(errors));
  return result;
}

}  // namespace fremen::model::testing
