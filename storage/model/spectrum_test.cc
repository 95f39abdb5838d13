#include "storage/model/spectrum.h"

#include <fftw3.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "storage/model/published_model.h"
#include "storage/model/test_signals.h"

namespace fremen::model {
namespace {

using testing::RandomTimes;
using testing::Sample;
using testing::SampleBernoulli;
using testing::UniformTimes;

template <typename Real>
double MaxGammaDifference(const BasicSpectrum<Real>& a, const BasicSpectrum<Real>& b) {
  double diff = std::fabs(a.gamma0() - b.gamma0());
  for (size_t k = 0; k < a.periods(); ++k) diff = std::max(diff, std::abs(a.gamma(k) - b.gamma(k)));
  return diff;
}

TEST(SpectrumTest, RecoversAKnownPeriodicSignalFromIrregularSamples) {
  const PeriodSet periods = PeriodSet::Default();
  const double amplitude = 0.3, phase = 1.1, period = 86400;
  const auto obs = Sample(RandomTimes(200000, 1.7e9, 8 * 604800.0, 7), [&](double t) {
    return static_cast<float>(0.5 + amplitude * std::cos(ReducedPhase(t, period) + phase));
  });
  Spectrum spectrum(periods.size());
  spectrum.AddBatch(obs, periods);
  const PublishedModel model = PublishedModel::FromSpectrum(spectrum, periods, 1, 1);
  ASSERT_EQ(model.components().size(), 1u);
  const Component& c = model.components()[0];
  EXPECT_NEAR(periods.period(c.k) / period, 1.0, 0.01);
  EXPECT_NEAR(c.amplitude(), amplitude, 0.01);
  EXPECT_NEAR(std::remainder(c.phase() - phase, 2 * M_PI), 0.0, 0.01);
  EXPECT_NEAR(model.alpha0(), 0.5, 0.01);
}

template <typename Real>
void CheckBatchAndOrderInvariance() {
  const PeriodSet periods = PeriodSet::Default();
  auto obs = SampleBernoulli(RandomTimes(20000, 1.6e9, 3 * 604800.0, 11),
                             [](double t) { return 0.5 + 0.4 * std::cos(ReducedPhase(t, 86400)); }, 12);
  BasicSpectrum<Real> one(periods.size());
  one.AddBatch(obs, periods);

  BasicSpectrum<Real> split(periods.size());
  std::mt19937_64 rng(5);
  std::vector<size_t> cuts(999);
  for (size_t& c : cuts) c = std::uniform_int_distribution<size_t>(0, obs.size())(rng);
  cuts.push_back(0);
  cuts.push_back(obs.size());
  std::sort(cuts.begin(), cuts.end());
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    split.AddBatch(std::span(obs).subspan(cuts[i], cuts[i + 1] - cuts[i]), periods);
  }

  std::shuffle(obs.begin(), obs.end(), rng);
  BasicSpectrum<Real> shuffled(periods.size());
  shuffled.AddBatch(obs, periods);

  BasicSpectrum<Real> one_by_one(periods.size());
  for (const Observation& o : obs) one_by_one.Observe(ScanPhasors<Real>(PhasorTable(periods, o.t)), o.s);

  EXPECT_EQ(split.count(), one.count());
  EXPECT_LT(MaxGammaDifference(one, split), 1e-5);
  EXPECT_LT(MaxGammaDifference(one, shuffled), 1e-5);
  EXPECT_LT(MaxGammaDifference(one, one_by_one), 1e-5);
  EXPECT_EQ(one.header().t_first, shuffled.header().t_first);
  EXPECT_EQ(one.header().t_last, split.header().t_last);
}

TEST(SpectrumTest, BatchingAndOrderDoNotMatterDouble) { CheckBatchAndOrderInvariance<double>(); }
TEST(SpectrumTest, BatchingAndOrderDoNotMatterFloat) { CheckBatchAndOrderInvariance<float>(); }

TEST(SpectrumTest, MergeEqualsUnion) {
  const PeriodSet periods = PeriodSet::Default();
  const auto a = SampleBernoulli(RandomTimes(5000, 0, 604800.0, 1), [](double) { return 0.2; }, 2);
  const auto b = SampleBernoulli(RandomTimes(7000, 3e5, 904800.0, 3),
                                 [](double t) { return 0.5 + 0.5 * std::cos(ReducedPhase(t, 43200)); }, 4);
  Spectrum sa(periods.size()), sb(periods.size()), both(periods.size());
  sa.AddBatch(a, periods);
  sb.AddBatch(b, periods);
  both.AddBatch(a, periods);
  both.AddBatch(b, periods);
  sa.Merge(sb);
  EXPECT_EQ(sa.count(), both.count());
  EXPECT_EQ(sa.header().t_first, both.header().t_first);
  EXPECT_EQ(sa.header().t_last, both.header().t_last);
  EXPECT_LT(MaxGammaDifference(sa, both), 1e-12);
}

TEST(SpectrumTest, EqualsFftwOnUniformSamplesAtTheFftBins) {
  const size_t m = 4096;
  const double step = 60.0;
  std::vector<double> bin_periods;
  for (size_t k = 1; k < m / 2; ++k) bin_periods.push_back(m * step / k);
  const PeriodSet periods = *PeriodSet::FromPeriods(bin_periods);
  const auto obs = SampleBernoulli(UniformTimes(m, 0, step),
                                   [](double t) { return 0.4 + 0.3 * std::sin(ReducedPhase(t, 3600 * 5.0)); }, 9);
  Spectrum spectrum(periods.size());
  spectrum.AddBatch(obs, periods);

  std::vector<double> x(m);
  for (size_t j = 0; j < m; ++j) x[j] = obs[j].s - spectrum.gamma0();
  std::vector<fftw_complex> out(m / 2 + 1);
  fftw_plan plan = fftw_plan_dft_r2c_1d(static_cast<int>(m), x.data(), out.data(), FFTW_ESTIMATE);
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  double worst = 0;
  for (size_t k = 1; k < m / 2; ++k) {
    const std::complex<double> fft(out[k][0] / m, out[k][1] / m);
    const std::complex<double> ours = spectrum.gamma(k - 1);
    worst = std::max(worst, std::abs(ours - fft) / std::max(std::abs(fft), 1e-300));
  }
  EXPECT_LT(worst, 1e-9);
}

// 10^8 observations one by one, with a short Ω and a cycle of precomputed phasor tables so the test
// measures the accumulation, not the trigonometry.
template <typename Real>
double ErrorAfterObservations(size_t observations) {
  const PeriodSet periods = *PeriodSet::FromPeriods({86400, 3600});
  constexpr size_t kTimes = 997;
  std::vector<ScanPhasors<Real>> tables;
  std::vector<std::complex<double>> s_sum(2), e_sum(2);
  double sum_s = 0;
  for (size_t i = 0; i < kTimes; ++i) tables.emplace_back(PhasorTable(periods, 1.7e9 + 61.3 * i));
  BasicSpectrum<Real> spectrum(periods.size());
  const size_t kObservations = observations;
  for (size_t i = 0; i < kObservations; ++i) {
    const float s = (i % 7 < 3) ? 1.0f : 0.0f;
    spectrum.Observe(tables[i % kTimes], s);
  }
  // Exact sums via counts per (table, value) pair, so the reference itself has no accumulated error.
  std::vector<double> count(kTimes * 2, 0);
  for (size_t i = 0; i < kObservations; ++i) count[(i % kTimes) * 2 + ((i % 7 < 3) ? 1 : 0)] += 1;
  for (size_t j = 0; j < kTimes; ++j) sum_s += count[j * 2 + 1];
  for (size_t j = 0; j < kTimes; ++j) {
    const PhasorTable table(periods, 1.7e9 + 61.3 * j);
    for (size_t k = 0; k < 2; ++k) {
      e_sum[k] += (count[j * 2] + count[j * 2 + 1]) * table.conj_phasor(k);
      s_sum[k] += count[j * 2 + 1] * table.conj_phasor(k);
    }
  }
  const double gamma0 = sum_s / kObservations;
  double worst = std::fabs(spectrum.gamma0() - gamma0);
  for (size_t k = 0; k < 2; ++k) {
    worst = std::max(worst, std::abs(spectrum.gamma(k) - (s_sum[k] - gamma0 * e_sum[k]) / double(kObservations)));
  }
  return worst;
}

TEST(SpectrumTest, AccurateAfterHundredMillionObservations) {
  EXPECT_LT(ErrorAfterObservations<double>(100'000'000), 1e-9);
}

// Float running means lose increments smaller than half an ulp once n grows (swamping), which is
// why a compact record is widened to double at kCompactRecordLimit observations.
TEST(SpectrumTest, CompactRecordIsAccurateUpToItsLimit) {
  EXPECT_LT(ErrorAfterObservations<float>(kCompactRecordLimit), 1e-4);
}

}  // namespace
}  // namespace fremen::model
