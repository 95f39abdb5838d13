#include "storage/model/published_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "storage/model/test_signals.h"

namespace fremen::model {
namespace {

using testing::RandomTimes;
using testing::Sample;

// 0.5 + 0.3 cos(daily) + 0.15 cos(weekly) + 0.05 cos(12 h), over `weeks` weeks.
Spectrum ThreeComponentSpectrum(const PeriodSet& periods, double weeks) {
  const auto obs = Sample(RandomTimes(100000, 0, weeks * 604800.0, 3), [](double t) {
    return static_cast<float>(0.5 + 0.3 * std::cos(ReducedPhase(t, 86400)) +
                              0.15 * std::cos(ReducedPhase(t, 604800)) + 0.05 * std::cos(ReducedPhase(t, 43200)));
  });
  Spectrum spectrum(periods.size());
  spectrum.AddBatch(obs, periods);
  return spectrum;
}

TEST(PublishedModelTest, KeepsTheStrongestComponentsSortedByAmplitudeWithFactorTwo) {
  const PeriodSet periods = PeriodSet::Default();
  const PublishedModel model = PublishedModel::FromSpectrum(ThreeComponentSpectrum(periods, 4), periods, 5, 3);
  ASSERT_EQ(model.components().size(), 5u);
  EXPECT_EQ(model.order(), 3);
  EXPECT_DOUBLE_EQ(periods.period(model.components()[0].k), 86400);
  EXPECT_DOUBLE_EQ(periods.period(model.components()[1].k), 604800);
  EXPECT_DOUBLE_EQ(periods.period(model.components()[2].k), 43200);
  EXPECT_NEAR(model.components()[0].amplitude(), 0.3, 0.01);
  EXPECT_NEAR(model.components()[1].amplitude(), 0.15, 0.01);
  for (size_t j = 1; j < model.components().size(); ++j) {
    EXPECT_GE(model.components()[j - 1].amplitude(), model.components()[j].amplitude());
  }
}

TEST(PublishedModelTest, PeriodsLongerThanTwoThirdsOfTheSpanAreNotEligible) {
  const PeriodSet periods = PeriodSet::Default();
  // One week of data: the weekly period (1.5·T > span) must not be published even though it is strong.
  const PublishedModel model = PublishedModel::FromSpectrum(ThreeComponentSpectrum(periods, 1), periods, 5, 5);
  for (const Component& c : model.components()) EXPECT_LE(periods.period(c.k), 604800.0 * 2 / 3);
}

TEST(PublishedModelTest, PredictsWithTheSelectedOrderOrAnOverrideAndClamps) {
  const PeriodSet periods = PeriodSet::Default();
  const PublishedModel model = PublishedModel::FromSpectrum(ThreeComponentSpectrum(periods, 4), periods, 5, 2);
  const double t = 3 * 86400 + 1000;
  const PhasorTable at(periods, t);
  const double truth2 = 0.5 + 0.3 * std::cos(ReducedPhase(t, 86400)) + 0.15 * std::cos(ReducedPhase(t, 604800));
  EXPECT_NEAR(model.Predict(at), truth2, 0.02);
  EXPECT_NEAR(model.Predict(at, 0), 0.5, 0.01);
  EXPECT_NEAR(model.Predict(at, 1), 0.5 + 0.3 * std::cos(ReducedPhase(t, 86400)), 0.02);
  // An order above the components held uses them all rather than reading past the end.
  EXPECT_NEAR(model.Predict(at, 60), model.Predict(at, 5), 1e-12);

  const PublishedModel big = PublishedModel::FromSpectrum(Spectrum(periods.size()), periods, 5, 0);
  EXPECT_DOUBLE_EQ(big.Predict(at), 0.5);  // no data: no information
  EXPECT_DOUBLE_EQ(PublishedModel::MeanOnly(1.7).Predict(at), 1.0);
  EXPECT_DOUBLE_EQ(PublishedModel::MeanOnly(-0.2).Predict(at), 0.0);
}

TEST(PublishedModelTest, AnomalyAtHighConfidenceWherePIsNearZeroAndStateIsOne) {
  EXPECT_TRUE(IsAnomalous(1.0, 0.001, 0.99));
  EXPECT_FALSE(IsAnomalous(0.0, 0.001, 0.99));
  EXPECT_TRUE(IsAnomalous(0.0, 0.999, 0.99));
  EXPECT_FALSE(IsAnomalous(1.0, 0.5, 0.99));  // uncertain: nothing is anomalous
  EXPECT_TRUE(EstimateState(0.7, 0.6));
  EXPECT_FALSE(EstimateState(0.7, 0.9));
}

TEST(PublishedModelTest, EntropyIsOneBitAtOneHalfAndZeroAtCertainty) {
  EXPECT_DOUBLE_EQ(Entropy(0.5), 1.0);
  EXPECT_DOUBLE_EQ(Entropy(0.0), 0.0);
  EXPECT_DOUBLE_EQ(Entropy(1.0), 0.0);
  EXPECT_NEAR(Entropy(0.1), 0.468996, 1e-6);
}

}  // namespace
}  // namespace fremen::model
