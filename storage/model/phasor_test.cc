#include "storage/model/phasor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "storage/model/periods.h"

namespace fremen::model {
namespace {

// The largest difference between a table and cos/sin of each period's own reduced phase, as a
// fraction of `allowed(k)`.
template <typename Allowed>
double WorstError(const PhasorTable& table, const PeriodSet& periods, double t, Allowed allowed) {
  double worst = 0;
  for (size_t k = 0; k < periods.size(); ++k) {
    const double phase = ReducedPhase(t, periods.period(k));
    const double error = std::max(std::fabs(table.cos(k) - std::cos(phase)), std::fabs(table.sin(k) - std::sin(phase)));
    worst = std::max(worst, error / allowed(k));
  }
  return worst;
}

TEST(PeriodSetTest, HarmonicOnlyWhenEveryPeriodIsTheFirstOverItsIndex) {
  EXPECT_TRUE(PeriodSet::Default().harmonic());
  EXPECT_TRUE(PeriodSet::Harmonics(86400, 7, false)->harmonic());
  EXPECT_TRUE(PeriodSet::FromPeriods({86400})->harmonic());
  EXPECT_TRUE(PeriodSet::FromPeriods({86400, 43200, 28800})->harmonic());
  EXPECT_FALSE(PeriodSet::FromPeriods({86400, 3600})->harmonic());
  EXPECT_FALSE(PeriodSet::FromPeriods({86400, 28800, 43200})->harmonic());
  // Periods floored to whole seconds are not exact harmonics past k = 10 (604800/11 → 54981 s).
  EXPECT_FALSE(PeriodSet::Harmonics(604800, 24, true)->harmonic());
}

TEST(PhasorTableTest, HarmonicTableMatchesEachPeriodsOwnPhase) {
  // The harmonic table raises e^{jω_1 t} to the powers 1..K; each period's own phase uses T_1/k
  // rounded to a double, whose relative error ε/2 turns into (t/T_k)·2π·ε/2 of phase (3e-11 for
  // K = 24 at t = 4e9, and it is the table that holds the exact harmonic). Besides that, the
  // powers' own rounding: a few ε per multiplication. Both far below a float's 6e-8.
  constexpr double kEpsilon = 2.220446049250313e-16;
  for (const int count : {1, 3, 4, 5, 24, 97, 1000}) {
    const PeriodSet periods = *PeriodSet::Harmonics(604800, count, false);
    ASSERT_TRUE(periods.harmonic());
    for (const double t : {0.0, 1.0, 1.7e9, 1.7e9 + 0.123, 4.1e9 - 7.77}) {
      const PhasorTable table(periods, t);
      ASSERT_EQ(table.size(), periods.size());
      const auto allowed = [&](size_t k) {
        return 2 * std::numbers::pi * (t / periods.period(k)) * kEpsilon / 2 + 4.0 * (k + 1) * kEpsilon + kEpsilon;
      };
      EXPECT_LE(WorstError(table, periods, t, allowed), 1.0) << "K " << count << " t " << t;
    }
  }
  // And the bound is not loose enough to pass a table of the wrong powers.
  const PeriodSet periods = PeriodSet::Default();
  const PhasorTable table(periods, 1.7e9);
  const PeriodSet shifted = *PeriodSet::Harmonics(604800 / 2.0, static_cast<int>(periods.size()), false);
  EXPECT_GT(WorstError(table, shifted, 1.7e9, [](size_t) { return 1e-6; }), 1.0);
}

TEST(PhasorTableTest, NonHarmonicTableIsEachPeriodsOwnPhase) {
  const PeriodSet periods = *PeriodSet::FromPeriods({86400, 3600, 7 * 86400 + 0.5});
  ASSERT_FALSE(periods.harmonic());
  const PhasorTable table(periods, 1.7e9 + 12.5);
  EXPECT_EQ(WorstError(table, periods, 1.7e9 + 12.5, [](size_t) { return 1.0; }), 0.0);
}

TEST(PhasorTableTest, ResetEqualsAFreshTable) {
  const PeriodSet periods = PeriodSet::Default();
  const PeriodSet other = *PeriodSet::FromPeriods({86400, 3600});
  PhasorTable table(other, 5.0);  // another Ω first: Reset must resize
  for (const double t : {1.7e9, 1.7e9 + 300.0, 1.6e9}) {
    table.Reset(periods, t);
    const PhasorTable fresh(periods, t);
    EXPECT_EQ(table.time(), t);
    ASSERT_EQ(table.size(), fresh.size());
    for (size_t k = 0; k < fresh.size(); ++k) {
      EXPECT_EQ(table.cos(k), fresh.cos(k)) << k;
      EXPECT_EQ(table.sin(k), fresh.sin(k)) << k;
      EXPECT_EQ(table.cos_f()[k], fresh.cos_f()[k]) << k;
      EXPECT_EQ(table.sin_f()[k], fresh.sin_f()[k]) << k;
    }
  }
}

// The float tables end with zeros up to whole vectors of kFloatLanes, also after a Reset to a smaller
// Ω (whose padding covers entries the larger one used).
TEST(PhasorTableTest, FloatTablesArePaddedWithZerosToWholeVectors) {
  const PeriodSet larger = *PeriodSet::Harmonics(604800, 31);
  const PeriodSet smaller = *PeriodSet::Harmonics(604800, 19);
  PhasorTable table(larger, 1.7e9);
  EXPECT_NE(table.cos_f()[30], 0.0f);
  table.Reset(smaller, 1.7e9 + 60.0);
  ASSERT_EQ(table.size(), 19u);
  static_assert(PhasorTable::kFloatLanes == 16);
  for (size_t k = 19; k < 32; ++k) {
    EXPECT_EQ(table.cos_f()[k], 0.0f) << k;
    EXPECT_EQ(table.sin_f()[k], 0.0f) << k;
  }
  EXPECT_NE(table.cos_f()[18], 0.0f);
}

}  // namespace
}  // namespace fremen::model
