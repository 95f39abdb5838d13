// The update scheduler's thread driven by a fake clock (no sleeps): the test moves the clock to
// each run the scheduler announces and records which maps it started, and when. Time zones and
// the daylight-saving nights of Europe/Prague in 2024 (spring forward on 31 March at 02:00 CET →
// 03:00 CEST, fall back on 27 October at 03:00 CEST → 02:00 CET), clock jumps, per-map schedules,
// a disabled schedule, and the options from the config.
#include "server/jobs/update_scheduler.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <mutex>
#include <utility>

#include "server/jobs/fake_clock.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;
using ::testing::UnorderedElementsAre;

absl::Time Utc(int y, int m, int d, int h, int min) {
  return absl::FromCivil(absl::CivilMinute(y, m, d, h, min), absl::UTCTimeZone());
}

absl::TimeZone Prague() {
  absl::TimeZone zone;
  EXPECT_TRUE(absl::LoadTimeZone("Europe/Prague", &zone));
  return zone;
}

CronSchedule Cron(const char* text) {
  auto schedule = CronSchedule::Parse(text);
  EXPECT_TRUE(schedule.ok()) << schedule.status();
  return *schedule;
}

UpdateScheduler::Options Daily(const char* cron, absl::TimeZone zone) {
  UpdateScheduler::Options options;
  options.schedule = Cron(cron);
  options.zone = zone;
  return options;
}

// A scheduler on a fake clock starting at `start`, over the maps `maps`, recording its triggers.
class Harness {
 public:
  Harness(UpdateScheduler::Options options, absl::Time start, std::vector<std::string> maps = {"lab"})
      : clock_(start),
        maps_(std::move(maps)),
        scheduler_(std::move(options), clock_, [this] { return ListMaps(); },
                   [this](const std::string& map) { Record(map); }) {
    scheduler_.Start();
  }

  // Moves the clock to each run the scheduler announces, up to `end` (then to `end`), letting the
  // scheduler catch up each time. Returns the runs: (time, map) in order.
  std::vector<std::pair<absl::Time, std::string>> RunUntil(absl::Time end) {
    while (true) {
      EXPECT_TRUE(clock_.AwaitWaiters(1)) << "the scheduler is not waiting";
      const absl::Time next = scheduler_.NextRun();
      if (next > end) break;
      clock_.Set(next);
    }
    clock_.Set(end);
    EXPECT_TRUE(clock_.AwaitWaiters(1));
    return Runs();
  }
  // Jumps the clock to `t` at once and lets the scheduler catch up.
  void Jump(absl::Time t) {
    EXPECT_TRUE(clock_.AwaitWaiters(1));
    clock_.Set(t);
    EXPECT_TRUE(clock_.AwaitWaiters(1));
  }
  std::vector<absl::Time> RunTimes() {
    std::vector<absl::Time> times;
    for (const auto& [t, map] : Runs()) times.push_back(t);
    return times;
  }
  std::vector<std::pair<absl::Time, std::string>> Runs() {
    std::lock_guard lock(mutex_);
    return runs_;
  }
  void FailListing() {
    std::lock_guard lock(mutex_);
    fail_listing_ = true;
  }
  UpdateScheduler& scheduler() { return scheduler_; }

 private:
  absl::StatusOr<std::vector<std::string>> ListMaps() {
    std::lock_guard lock(mutex_);
    if (fail_listing_) return absl::UnavailableError("store recovering");
    return maps_;
  }
  void Record(const std::string& map) {
    std::lock_guard lock(mutex_);
    runs_.emplace_back(clock_.Now(), map);
  }

  FakeClock clock_;
  std::mutex mutex_;
  std::vector<std::string> maps_;
  std::vector<std::pair<absl::Time, std::string>> runs_;
  bool fail_listing_ = false;
  UpdateScheduler scheduler_;  // last: its thread uses the members above
};

TEST(UpdateSchedulerTest, MidnightInPragueAcrossSpringForward) {
  // Midnight CET is 23:00 UTC the day before; from 31 March, midnight CEST is 22:00 UTC.
  Harness h(Daily("0 0 * * *", Prague()), Utc(2024, 3, 29, 12, 0));
  h.RunUntil(Utc(2024, 4, 2, 12, 0));
  EXPECT_THAT(h.RunTimes(), ElementsAre(Utc(2024, 3, 29, 23, 0), Utc(2024, 3, 30, 23, 0), Utc(2024, 3, 31, 22, 0),
                                        Utc(2024, 4, 1, 22, 0)));
}

TEST(UpdateSchedulerTest, MidnightInPragueAcrossFallBack) {
  // 26 → 27 October is 24 h, 27 → 28 October 25 h (the night of the fall-back).
  Harness h(Daily("0 0 * * *", Prague()), Utc(2024, 10, 25, 12, 0));
  h.RunUntil(Utc(2024, 10, 28, 12, 0));
  EXPECT_THAT(h.RunTimes(),
              ElementsAre(Utc(2024, 10, 25, 22, 0), Utc(2024, 10, 26, 22, 0), Utc(2024, 10, 27, 23, 0)));
}

TEST(UpdateSchedulerTest, SkippedMinuteRunsWhenTheJumpLands) {
  // 02:30 does not exist on 31 March in Prague: the run is at 03:00 CEST (01:00 UTC), once.
  Harness h(Daily("30 2 * * *", Prague()), Utc(2024, 3, 30, 0, 0));
  h.RunUntil(Utc(2024, 4, 1, 12, 0));
  EXPECT_THAT(h.RunTimes(), ElementsAre(Utc(2024, 3, 30, 1, 30), Utc(2024, 3, 31, 1, 0), Utc(2024, 4, 1, 0, 30)));
}

TEST(UpdateSchedulerTest, RepeatedMinuteRunsOnce) {
  // 02:30 happens twice on 27 October in Prague (00:30 UTC in CEST, 01:30 UTC in CET): one run, the first.
  Harness h(Daily("30 2 * * *", Prague()), Utc(2024, 10, 26, 0, 0));
  h.RunUntil(Utc(2024, 10, 28, 12, 0));
  EXPECT_THAT(h.RunTimes(),
              ElementsAre(Utc(2024, 10, 26, 0, 30), Utc(2024, 10, 27, 0, 30), Utc(2024, 10, 28, 1, 30)));
}

TEST(UpdateSchedulerTest, HourlyAcrossTheFallBackNight) {
  // Local hours 01:00, 02:00 (CEST), 03:00 (CET): the repeated 02:00 CET is the same local minute
  // and runs once, so the UTC gap around it is two hours.
  Harness h(Daily("0 * * * *", Prague()), Utc(2024, 10, 26, 22, 30));
  h.RunUntil(Utc(2024, 10, 27, 3, 30));
  EXPECT_THAT(h.RunTimes(), ElementsAre(Utc(2024, 10, 26, 23, 0), Utc(2024, 10, 27, 0, 0), Utc(2024, 10, 27, 2, 0),
                                        Utc(2024, 10, 27, 3, 0)));
}

TEST(UpdateSchedulerTest, TheZoneDecidesTheInstant) {
  Harness utc(Daily("0 0 * * *", absl::UTCTimeZone()), Utc(2024, 7, 1, 12, 0));
  utc.RunUntil(Utc(2024, 7, 3, 0, 0));
  EXPECT_THAT(utc.RunTimes(), ElementsAre(Utc(2024, 7, 2, 0, 0), Utc(2024, 7, 3, 0, 0)));
  Harness prague(Daily("0 0 * * *", Prague()), Utc(2024, 7, 1, 12, 0));
  prague.RunUntil(Utc(2024, 7, 3, 0, 0));
  EXPECT_THAT(prague.RunTimes(), ElementsAre(Utc(2024, 7, 1, 22, 0), Utc(2024, 7, 2, 22, 0)));
}

TEST(UpdateSchedulerTest, NothingRunsBeforeItsMinute) {
  Harness h(Daily("0 0 * * *", absl::UTCTimeZone()), Utc(2024, 7, 1, 12, 0));
  h.Jump(Utc(2024, 7, 1, 23, 59) + absl::Seconds(59));
  EXPECT_THAT(h.Runs(), IsEmpty());
  h.Jump(Utc(2024, 7, 2, 0, 0));
  EXPECT_THAT(h.RunTimes(), ElementsAre(Utc(2024, 7, 2, 0, 0)));
}

TEST(UpdateSchedulerTest, AJumpOverSeveralRunsGivesOne) {
  Harness h(Daily("0 0 * * *", absl::UTCTimeZone()), Utc(2024, 7, 1, 12, 0));
  h.Jump(Utc(2024, 7, 4, 6, 0));  // a machine suspended for three days
  EXPECT_THAT(h.RunTimes(), ElementsAre(Utc(2024, 7, 4, 6, 0)));
  EXPECT_EQ(h.scheduler().NextRun(), Utc(2024, 7, 5, 0, 0));
}

TEST(UpdateSchedulerTest, EveryMapRunsAndOverridesReplaceTheDefault) {
  UpdateScheduler::Options options = Daily("0 0 * * *", absl::UTCTimeZone());
  options.overrides["night"] = Cron("0 3 * * *");
  options.overrides["manual"] = std::nullopt;  // on demand only
  options.overrides["gone"] = Cron("0 1 * * *");  // a map that does not exist: nothing to run
  Harness h(std::move(options), Utc(2024, 7, 1, 12, 0), {"lab", "manual", "night", "yard"});
  const auto runs = h.RunUntil(Utc(2024, 7, 2, 12, 0));
  ASSERT_EQ(runs.size(), 3u);
  std::vector<std::string> at_midnight;
  for (const auto& [t, map] : runs) {
    if (t == Utc(2024, 7, 2, 0, 0)) at_midnight.push_back(map);
  }
  EXPECT_THAT(at_midnight, UnorderedElementsAre("lab", "yard"));
  EXPECT_EQ(runs.back(), std::make_pair(Utc(2024, 7, 2, 3, 0), std::string("night")));
}

TEST(UpdateSchedulerTest, DisabledScheduleNeverRuns) {
  FakeClock clock(Utc(2024, 7, 1, 12, 0));
  int triggered = 0;
  UpdateScheduler scheduler(UpdateScheduler::Options(), clock,
                            [] { return std::vector<std::string>{"lab"}; }, [&](const std::string&) { ++triggered; });
  EXPECT_EQ(scheduler.NextRun(), absl::InfiniteFuture());
  scheduler.Start();  // starts no thread
  clock.Advance(absl::Hours(24 * 30));
  scheduler.Stop();
  EXPECT_EQ(triggered, 0);
}

TEST(UpdateSchedulerTest, ARunThatCannotListTheMapsIsSkipped) {
  Harness h(Daily("0 0 * * *", absl::UTCTimeZone()), Utc(2024, 7, 1, 12, 0));
  h.FailListing();
  h.RunUntil(Utc(2024, 7, 2, 12, 0));
  EXPECT_THAT(h.Runs(), IsEmpty());
  EXPECT_EQ(h.scheduler().NextRun(), Utc(2024, 7, 3, 0, 0));
}

TEST(UpdateSchedulerTest, OptionsFromConfig) {
  ServerConfig config;
  config.update_schedule = "15 4 * * 1-5";
  config.update_time_zone = "Europe/Prague";
  auto options = SchedulerOptionsFromConfig(config);
  ASSERT_TRUE(options.ok()) << options.status();
  ASSERT_TRUE(options->schedule.has_value());
  EXPECT_EQ(options->schedule->text(), "15 4 * * 1-5");
  EXPECT_EQ(options->zone.name(), "Europe/Prague");
  EXPECT_TRUE(options->overrides.empty());

  config.update_schedule = "";
  config.update_time_zone = "local";
  options = SchedulerOptionsFromConfig(config);
  ASSERT_TRUE(options.ok());
  EXPECT_FALSE(options->schedule.has_value());

  config.update_time_zone = "Mars/Olympus_Mons";
  EXPECT_EQ(SchedulerOptionsFromConfig(config).status().code(), absl::StatusCode::kInvalidArgument);
  config.update_time_zone = "UTC";
  config.update_schedule = "0 24 * * *";
  const absl::Status bad = SchedulerOptionsFromConfig(config).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(bad.message()), ::testing::HasSubstr("update_schedule: hour"));
}

TEST(UpdateSchedulerTest, PerMapOverridesFromConfig) {
  ServerConfig config;
  config.update_schedule = "0 0 * * *";
  config.update_time_zone = "UTC";
  config.update_map_schedules = {{"lab", "30 2 * * *"}, {"yard", ""}};
  auto options = SchedulerOptionsFromConfig(config);
  ASSERT_TRUE(options.ok()) << options.status();
  ASSERT_EQ(options->overrides.size(), 2u);
  ASSERT_TRUE(options->overrides.at("lab").has_value());
  EXPECT_EQ(options->overrides.at("lab")->text(), "30 2 * * *");
  EXPECT_FALSE(options->overrides.at("yard").has_value()) << "never: on demand only";

  config.update_map_schedules = {{"lab", "61 2 * * *"}};
  const absl::Status bad = SchedulerOptionsFromConfig(config).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(bad.message()), ::testing::HasSubstr("update_map_schedules: map \"lab\": minute"));
}

}  // namespace
}  // namespace fremen::server
