#include "server/jobs/cron.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

absl::Time Utc(int y, int mo, int d, int h, int mi) {
  return absl::FromCivil(absl::CivilMinute(y, mo, d, h, mi), absl::UTCTimeZone());
}

TEST(CronScheduleTest, DailyAtMidnightIsTheDefault) {
  auto schedule = CronSchedule::Parse("0 0 * * *");
  ASSERT_TRUE(schedule.ok()) << schedule.status();
  EXPECT_TRUE(schedule->Matches(absl::CivilMinute(2024, 3, 5, 0, 0)));
  EXPECT_FALSE(schedule->Matches(absl::CivilMinute(2024, 3, 5, 0, 1)));
  EXPECT_EQ(schedule->Next(Utc(2024, 3, 5, 13, 7), absl::UTCTimeZone()), Utc(2024, 3, 6, 0, 0));
  // Strictly after: at midnight itself, the next is the following midnight.
  EXPECT_EQ(schedule->Next(Utc(2024, 3, 6, 0, 0), absl::UTCTimeZone()), Utc(2024, 3, 7, 0, 0));
}

TEST(CronScheduleTest, ListsRangesAndSteps) {
  auto schedule = CronSchedule::Parse("*/15 8-10,22 * * 1-5");
  ASSERT_TRUE(schedule.ok()) << schedule.status();
  EXPECT_TRUE(schedule->Matches(absl::CivilMinute(2024, 3, 4, 8, 45)));   // Monday
  EXPECT_TRUE(schedule->Matches(absl::CivilMinute(2024, 3, 8, 22, 0)));   // Friday
  EXPECT_FALSE(schedule->Matches(absl::CivilMinute(2024, 3, 4, 11, 0)));  // hour not listed
  EXPECT_FALSE(schedule->Matches(absl::CivilMinute(2024, 3, 4, 9, 10)));  // not a quarter
  EXPECT_FALSE(schedule->Matches(absl::CivilMinute(2024, 3, 9, 9, 0)));   // Saturday
}

TEST(CronScheduleTest, SevenIsSunday) {
  auto schedule = CronSchedule::Parse("0 3 * * 7");
  ASSERT_TRUE(schedule.ok()) << schedule.status();
  EXPECT_TRUE(schedule->Matches(absl::CivilMinute(2024, 3, 10, 3, 0)));  // Sunday
  EXPECT_FALSE(schedule->Matches(absl::CivilMinute(2024, 3, 11, 3, 0)));
}

TEST(CronScheduleTest, RestrictedDayFieldsMatchEither) {
  // Classic cron: the 1st of the month or any Monday.
  auto schedule = CronSchedule::Parse("0 0 1 * 1");
  ASSERT_TRUE(schedule.ok()) << schedule.status();
  EXPECT_TRUE(schedule->Matches(absl::CivilMinute(2024, 3, 1, 0, 0)));   // Friday the 1st
  EXPECT_TRUE(schedule->Matches(absl::CivilMinute(2024, 3, 4, 0, 0)));   // Monday the 4th
  EXPECT_FALSE(schedule->Matches(absl::CivilMinute(2024, 3, 5, 0, 0)));
}

TEST(CronScheduleTest, NextFollowsTheTimeZone) {
  absl::TimeZone prague;
  ASSERT_TRUE(absl::LoadTimeZone("Europe/Prague", &prague));
  auto schedule = CronSchedule::Parse("0 0 * * *");
  ASSERT_TRUE(schedule.ok());
  // Midnight in Prague in winter is 23:00 UTC the day before.
  EXPECT_EQ(schedule->Next(Utc(2024, 1, 10, 12, 0), prague), Utc(2024, 1, 10, 23, 0));
}

TEST(CronScheduleTest, NeverFiringScheduleHasNoNext) {
  auto schedule = CronSchedule::Parse("0 0 30 2 *");
  ASSERT_TRUE(schedule.ok());
  EXPECT_EQ(schedule->Next(Utc(2024, 1, 1, 0, 0), absl::UTCTimeZone()), absl::InfiniteFuture());
}

TEST(CronScheduleTest, ErrorsNameTheField) {
  EXPECT_THAT(CronSchedule::Parse("0 24 * * *").status().message(), HasSubstr("hour: 24 is outside [0, 23]"));
  EXPECT_THAT(CronSchedule::Parse("x 0 * * *").status().message(), HasSubstr("minute: \"x\" is not a number"));
  EXPECT_THAT(CronSchedule::Parse("0 0 0 * *").status().message(), HasSubstr("day of month: 0 is outside"));
  EXPECT_THAT(CronSchedule::Parse("0 0 * 13 *").status().message(), HasSubstr("month: 13 is outside"));
  EXPECT_THAT(CronSchedule::Parse("0 0 * * 8").status().message(), HasSubstr("day of week: 8 is outside"));
  EXPECT_THAT(CronSchedule::Parse("*/0 0 * * *").status().message(), HasSubstr("minute: step \"0\""));
  EXPECT_THAT(CronSchedule::Parse("0 5-2 * * *").status().message(), HasSubstr("hour: range \"5-2\" is empty"));
  EXPECT_THAT(CronSchedule::Parse("0 0 * *").status().message(), HasSubstr("has 4 fields"));
  EXPECT_THAT(CronSchedule::Parse("").status().message(), HasSubstr("has 0 fields"));
}

}  // namespace
}  // namespace fremen::server
