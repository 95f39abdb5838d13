#include "storage/model/periods.h"

#include <gtest/gtest.h>

#include <cmath>

#include "storage/model/phasor.h"

namespace fremen::model {
namespace {

TEST(PeriodSetTest, DefaultIsAWeekDownToSevenHours) {
  const PeriodSet periods = PeriodSet::Default();
  ASSERT_EQ(periods.size(), 24u);
  EXPECT_DOUBLE_EQ(periods.period(0), 604800.0);
  EXPECT_DOUBLE_EQ(periods.period(6), 86400.0);
  EXPECT_DOUBLE_EQ(periods.period(23), 25200.0);
}

TEST(PeriodSetTest, FloorPeriodsMatchTheOriginal) {
  const auto periods = PeriodSet::Harmonics(604800, 100, /*floor_periods=*/true);
  ASSERT_TRUE(periods.ok());
  EXPECT_DOUBLE_EQ(periods->period(10), std::floor(604800.0 / 11));
  EXPECT_DOUBLE_EQ(periods->period(99), 6048.0);
}

TEST(PeriodSetTest, RejectsBadArgumentsByName) {
  EXPECT_FALSE(PeriodSet::Harmonics(0, 24).ok());
  EXPECT_FALSE(PeriodSet::Harmonics(NAN, 24).ok());
  EXPECT_FALSE(PeriodSet::Harmonics(604800, 0).ok());
  EXPECT_FALSE(PeriodSet::Harmonics(604800, 70000).ok());
  const auto bad = PeriodSet::FromPeriods({86400, -1});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("periods[1]"), std::string::npos);
}

TEST(PhasorTest, RangeReductionKeepsEpochTimesExact) {
  // 1.7e9 s is an exact multiple of neither period; the reduced phase must match the phase of the
  // same instant measured from an origin close to it.
  const double period = 604800.0 / 11;
  const double t = 1.7e9 + 1234.5;
  const double local = std::fmod(t, period);
  EXPECT_NEAR(std::cos(ReducedPhase(t, period)), std::cos(2 * M_PI * local / period), 1e-12);
  // And float arithmetic would have been far off: ulp(1.7e9f) = 128 s.
  EXPECT_GT(std::fabs(static_cast<float>(t) - t), 1.0);
}

}  // namespace
}  // namespace fremen::model
