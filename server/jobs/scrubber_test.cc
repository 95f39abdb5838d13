// The background scrub's thread driven by a fake clock (no sleeps): a pass is due one interval
// after Start and one interval after the end of the previous pass; each map's latest result is
// kept (problems capped, records summed), maps no longer listed are dropped, a map whose check
// fails is skipped, each map's check is given scrub_map_timeout and one that runs out of it is
// reported unclean while the pass goes on, and an interval of 0 starts nothing.
#include "server/jobs/scrubber.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "server/jobs/fake_clock.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;

const absl::Time kStart = absl::FromUnixSeconds(1'700'000'000);
constexpr absl::Duration kInterval = absl::Hours(6);
constexpr absl::Duration kWait = absl::Seconds(30);  // only a stuck thread reaches it

storage::VerifyReport Report(const std::string& map, size_t problems, uint64_t records_per_shard) {
  storage::VerifyReport report;
  report.map = map;
  for (uint32_t shard = 0; shard < 2; ++shard) {
    storage::ShardVerifyReport s;
    s.shard = shard;
    s.records = records_per_shard;
    report.shards.push_back(s);
  }
  for (size_t i = 0; i < problems; ++i) {
    report.problems.push_back({"shard-1/data.mdb", "dynamic record of state " + std::to_string(i), "checksum mismatch"});
  }
  return report;
}

// Lists `maps` and answers each check from `reports` (a map without one is an error), recording the
// checks made; `during_check` runs inside each check (to move the clock as a slow check would).
struct FakeStore {
  std::mutex mutex;
  std::vector<std::string> maps;
  std::vector<std::string> checked;
  std::function<void()> during_check;

  Scrubber::MapLister Lister() {
    return [this]() -> absl::StatusOr<std::vector<std::string>> {
      std::lock_guard lock(mutex);
      return maps;
    };
  }
  Scrubber::Check Checker() {
    return [this](const std::string& map, absl::Time) -> absl::StatusOr<storage::VerifyReport> {
      std::function<void()> during;
      {
        std::lock_guard lock(mutex);
        checked.push_back(map);
        during = during_check;
      }
      if (during) during();
      if (map == "bad") return Report(map, 25, 7);
      if (map == "gone") return absl::NotFoundError("map gone was deleted");
      return Report(map, 0, 10);
    };
  }
  std::vector<std::string> Checked() {
    std::lock_guard lock(mutex);
    return checked;
  }
};

Scrubber::Options Every(absl::Duration interval) {
  Scrubber::Options options;
  options.interval = interval;
  options.low_priority = false;
  return options;
}

TEST(ScrubberTest, AnIntervalOfZeroStartsNothing) {
  FakeClock clock(kStart);
  FakeStore store;
  store.maps = {"a"};
  Scrubber scrubber(Every(absl::ZeroDuration()), clock, store.Lister(), store.Checker());
  scrubber.Start();
  EXPECT_FALSE(scrubber.enabled());
  EXPECT_EQ(scrubber.NextPass(), absl::InfiniteFuture());
  // A started thread would be waiting on the clock for its first pass: none is.
  EXPECT_FALSE(clock.AwaitWaiters(1, std::chrono::seconds(1)));
  clock.Advance(absl::Hours(1000));
  EXPECT_FALSE(scrubber.AwaitPasses(1, absl::ZeroDuration()));
  EXPECT_THAT(store.Checked(), IsEmpty());
}

TEST(ScrubberTest, APassIsDueOneIntervalAfterStartAndChecksEveryMapInOrder) {
  FakeClock clock(kStart);
  FakeStore store;
  store.maps = {"a", "bad"};
  Scrubber scrubber(Every(kInterval), clock, store.Lister(), store.Checker());
  scrubber.Start();
  EXPECT_EQ(scrubber.NextPass(), kStart + kInterval);

  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval - absl::Seconds(1));
  ASSERT_TRUE(clock.AwaitWaiters(1));  // woken, found nothing due, waiting again
  EXPECT_THAT(store.Checked(), IsEmpty());
  EXPECT_THAT(scrubber.Results(), IsEmpty());

  clock.Advance(absl::Seconds(1));
  ASSERT_TRUE(scrubber.AwaitPasses(1, kWait));
  EXPECT_THAT(store.Checked(), ElementsAre("a", "bad"));
  const std::vector<Scrubber::Result> results = scrubber.Results();
  ASSERT_EQ(results.size(), 2u);
  EXPECT_EQ(results[0].map, "a");
  EXPECT_TRUE(results[0].clean);
  EXPECT_EQ(results[0].problem_count, 0u);
  EXPECT_EQ(results[0].records, 20u);
  EXPECT_EQ(results[0].finished, kStart + kInterval);
  EXPECT_EQ(results[1].map, "bad");
  EXPECT_FALSE(results[1].clean);
  EXPECT_EQ(results[1].problem_count, 25u);
  ASSERT_EQ(results[1].problems.size(), Scrubber::kMaxProblemsKept);
  EXPECT_EQ(results[1].problems[0].where, "dynamic record of state 0");
  EXPECT_EQ(results[1].records, 14u);
  scrubber.Stop();
  EXPECT_EQ(scrubber.NextPass(), absl::InfiniteFuture());
}

TEST(ScrubberTest, TheNextPassIsOneIntervalAfterTheEndOfASlowPass) {
  FakeClock clock(kStart);
  FakeStore store;
  store.maps = {"a"};
  store.during_check = [&clock] { clock.Advance(absl::Hours(1)); };  // each check takes an hour
  Scrubber scrubber(Every(kInterval), clock, store.Lister(), store.Checker());
  scrubber.Start();
  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval);
  ASSERT_TRUE(scrubber.AwaitPasses(1, kWait));
  const std::vector<Scrubber::Result> results = scrubber.Results();
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].took, absl::Hours(1));
  EXPECT_EQ(scrubber.NextPass(), kStart + kInterval + absl::Hours(1) + kInterval);
}

TEST(ScrubberTest, MapsNoLongerListedAreDroppedAndAFailedCheckSkipsItsMap) {
  FakeClock clock(kStart);
  FakeStore store;
  store.maps = {"a", "bad"};
  Scrubber scrubber(Every(kInterval), clock, store.Lister(), store.Checker());
  scrubber.Start();
  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval);
  ASSERT_TRUE(scrubber.AwaitPasses(1, kWait));
  {
    std::lock_guard lock(store.mutex);
    store.maps = {"bad", "gone"};
  }
  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval);
  ASSERT_TRUE(scrubber.AwaitPasses(2, kWait));
  EXPECT_THAT(store.Checked(), ElementsAre("a", "bad", "bad", "gone"));
  const std::vector<Scrubber::Result> results = scrubber.Results();
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].map, "bad");
  EXPECT_EQ(results[0].finished, kStart + 2 * kInterval);
}

TEST(ScrubberTest, AListingErrorSkipsThePassAndTheNextOneComes) {
  FakeClock clock(kStart);
  bool fail = true;
  std::mutex mutex;
  std::vector<std::string> checked;
  Scrubber scrubber(
      Every(kInterval), clock,
      [&]() -> absl::StatusOr<std::vector<std::string>> {
        std::lock_guard lock(mutex);
        if (fail) return absl::UnavailableError("recovering");
        return std::vector<std::string>{"a"};
      },
      [&](const std::string& map, absl::Time) -> absl::StatusOr<storage::VerifyReport> {
        std::lock_guard lock(mutex);
        checked.push_back(map);
        return Report(map, 0, 1);
      });
  scrubber.Start();
  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval);
  ASSERT_TRUE(scrubber.AwaitPasses(1, kWait));
  {
    std::lock_guard lock(mutex);
    EXPECT_THAT(checked, IsEmpty());
    fail = false;
  }
  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval);
  ASSERT_TRUE(scrubber.AwaitPasses(2, kWait));
  std::lock_guard lock(mutex);
  EXPECT_THAT(checked, ElementsAre("a"));
}

}  // namespace
}  // namespace fremen::server

namespace fremen::server {
namespace {

// Each check is given a deadline of map_timeout from its start (real time: the verifier's reading
// child is killed by it); a map whose check ran out of it is kept as not clean, with the verifier's
// "not verified" problem, and the pass goes on with the next map.
TEST(ScrubberTest, EachMapsCheckIsBoundedByTheMapTimeoutAndAnOverrunIsReported) {
  FakeClock clock(kStart);
  constexpr absl::Duration kMapTimeout = absl::Minutes(7);
  std::mutex mutex;
  std::vector<std::pair<std::string, absl::Duration>> deadlines;  // map, deadline - call time
  Scrubber::Options options = Every(kInterval);
  options.map_timeout = kMapTimeout;
  Scrubber scrubber(
      options, clock, []() -> absl::StatusOr<std::vector<std::string>> { return std::vector<std::string>{"hung", "b"}; },
      [&](const std::string& map, absl::Time deadline) -> absl::StatusOr<storage::VerifyReport> {
        const absl::Time called = absl::Now();
        std::lock_guard lock(mutex);
        deadlines.emplace_back(map, deadline - called);
        storage::VerifyReport report = Report(map, 0, 3);
        if (map == "hung") {
          report.deadline_exceeded = true;
          report.problems.push_back({"shard-0/data.mdb", "", "not verified: the reading process had not finished"});
        }
        return report;
      });
  scrubber.Start();
  ASSERT_TRUE(clock.AwaitWaiters(1));
  clock.Advance(kInterval);
  ASSERT_TRUE(scrubber.AwaitPasses(1, kWait));
  {
    std::lock_guard lock(mutex);
    ASSERT_EQ(deadlines.size(), 2u);
    for (const auto& [map, left] : deadlines) {
      EXPECT_LE(left, kMapTimeout) << map;
      EXPECT_GT(left, kMapTimeout - absl::Seconds(30)) << map;  // set at the call, not at Start
    }
  }
  const std::vector<Scrubber::Result> results = scrubber.Results();
  ASSERT_EQ(results.size(), 2u);
  EXPECT_EQ(results[0].map, "b");
  EXPECT_TRUE(results[0].clean);
  EXPECT_EQ(results[1].map, "hung");
  EXPECT_FALSE(results[1].clean);
  ASSERT_EQ(results[1].problems.size(), 1u);
  EXPECT_EQ(results[1].problems[0].what, "not verified: the reading process had not finished");
}

}  // namespace
}  // namespace fremen::server
