// The operation registry with a scripted job that stops at gates the test opens, and a fake
// clock: one update per map at a time, queueing, cancellation at every stage, progress figures,
// listing and paging, retention, stopping.
#include "server/jobs/operations.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <sstream>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "absl/container/flat_hash_map.h"
#include "server/jobs/fake_clock.h"
#include "server/rpc/logging.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr auto kTimeout = std::chrono::seconds(30);

// A job in steps, each behind a gate the test opens: 1 = entered (before BeginPublishing), 2 =
// publishing, half done, 3 = finished. Map "broken" fails at once.
class ScriptedJob {
 public:
  UpdateJob job() {
    return [this](JobControl& control) -> absl::StatusOr<UpdateFigures> {
      const std::string& map = control.map();
      if (map == "broken") return absl::InternalError("disk on fire");
      Reach(map, 1);
      if (!control.BeginPublishing()) return absl::CancelledError("job saw the cancellation");
      control.Progress(50, 100);
      Reach(map, 2);
      control.Progress(100, 100);
      UpdateFigures figures;
      figures.states_published = 100;
      figures.order_histogram = {60, 40};
      figures.prediction_error_before = 0.3;
      figures.prediction_error_after = 0.2;
      return figures;
    };
  }
  // Waits until the job of `map` has reached `step`.
  bool AwaitStep(const std::string& map, int step) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, kTimeout, [&] { return reached_[map] >= step; });
  }
  // Lets the job of `map` go past `step`.
  void Open(const std::string& map, int step) {
    std::lock_guard lock(mutex_);
    open_[map] = step;
    changed_.notify_all();
  }
  int runs(const std::string& map) {
    std::lock_guard lock(mutex_);
    return reached_[map] >= 1;
  }

 private:
  void Reach(const std::string& map, int step) {
    std::unique_lock lock(mutex_);
    reached_[map] = step;
    changed_.notify_all();
    changed_.wait_for(lock, kTimeout, [&] { return open_[map] >= step; });
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  absl::flat_hash_map<std::string, int> reached_, open_;
};

class OperationsTest : public ::testing::Test {
 protected:
  // Waits until `name` is done (the registry's thread finishes it after the gate opens).
  OperationView AwaitDone(const std::string& name) {
    const auto deadline = std::chrono::steady_clock::now() + kTimeout;
    while (std::chrono::steady_clock::now() < deadline) {
      auto op = registry_.Get(name);
      if (op.ok() && op->done()) return *op;
      std::unique_lock lock(poll_mutex_);
      poll_.wait_for(lock, std::chrono::milliseconds(1));  // the registry has no completion hook to wait on
    }
    ADD_FAILURE() << name << " did not finish";
    return {};
  }

  FakeClock clock_{absl::FromUnixSeconds(1'700'000'000)};
  ScriptedJob job_;
  OperationRegistry::Options options_;
  OperationRegistry registry_{job_.job(), clock_, options_};
  std::mutex poll_mutex_;
  std::condition_variable poll_;
};

TEST_F(OperationsTest, SecondTriggerReturnsTheRunningOperation) {
  auto first = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(first->name, "operations/update-lab-1");
  EXPECT_EQ(first->map, "lab");
  EXPECT_FALSE(first->done());
  ASSERT_TRUE(job_.AwaitStep("lab", 1));
  auto second = registry_.StartUpdate("lab", "schedule");
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(second->name, first->name);
  EXPECT_EQ(second->trigger, "RunUpdate");
  EXPECT_EQ(registry_.running(), 1u);
  job_.Open("lab", 2);
  const OperationView done = AwaitDone(first->name);
  EXPECT_TRUE(done.error.ok()) << done.error;
  // Once done, a trigger starts a new update.
  auto third = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(third.ok());
  EXPECT_EQ(third->name, "operations/update-lab-2");
  job_.Open("lab", 2);
  AwaitDone(third->name);
}

TEST_F(OperationsTest, ResultAndProgressReachTheTotal) {
  auto op = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(op.ok());
  ASSERT_TRUE(job_.AwaitStep("lab", 1));
  clock_.Advance(absl::Seconds(1));
  job_.Open("lab", 1);
  ASSERT_TRUE(job_.AwaitStep("lab", 2));
  // Publishing started at t+1 s, reported 50 of 100 at t+1 s; the clock moves on 2 s.
  auto half = registry_.Get(op->name);
  ASSERT_TRUE(half.ok());
  EXPECT_EQ(half->stage, OperationStage::kPublishing);
  EXPECT_EQ(half->states_done, 50u);
  EXPECT_EQ(half->states_total, 100u);
  clock_.Advance(absl::Seconds(2));
  job_.Open("lab", 2);
  const OperationView done = AwaitDone(op->name);
  EXPECT_TRUE(done.error.ok());
  EXPECT_EQ(done.states_done, 100u);
  EXPECT_EQ(done.states_total, 100u);
  EXPECT_DOUBLE_EQ(done.rate, 100.0 / 3.0);  // 100 states over the 3 s since it started running
  ASSERT_TRUE(done.result.has_value());
  EXPECT_EQ(done.result->states_published, 100u);
  EXPECT_EQ(done.result->duration, absl::Seconds(3));
  EXPECT_THAT(done.result->order_histogram, ElementsAre(60, 40));
  EXPECT_EQ(done.end_time, clock_.Now());
  EXPECT_EQ(done.message, "done");
}

TEST_F(OperationsTest, RateAndEtaWhilePublishing) {
  auto op = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(op.ok());
  ASSERT_TRUE(job_.AwaitStep("lab", 1));
  job_.Open("lab", 1);
  ASSERT_TRUE(job_.AwaitStep("lab", 2));
  // The job reported 50/100 at the instant publishing began; report again 2 s later via a second
  // JobControl on the same operation, as a shard thread would.
  clock_.Advance(absl::Seconds(2));
  JobControl control(&registry_, op->id, "lab");
  control.Progress(60, 100);
  auto now = registry_.Get(op->name);
  ASSERT_TRUE(now.ok());
  EXPECT_DOUBLE_EQ(now->rate, 30.0);
  EXPECT_DOUBLE_EQ(now->eta_seconds, 40.0 / 30.0);
  job_.Open("lab", 2);
  AwaitDone(op->name);
}

TEST_F(OperationsTest, ProgressIsLoggedAtASteadyCadence) {
  // The daemon's logger, into a string.
  std::ostringstream log;
  auto logger = std::make_shared<spdlog::logger>(kDaemonLogger, std::make_shared<spdlog::sinks::ostream_sink_mt>(log));
  spdlog::drop(kDaemonLogger);
  spdlog::register_logger(logger);
  auto op = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(op.ok());
  ASSERT_TRUE(job_.AwaitStep("lab", 1));
  job_.Open("lab", 1);
  ASSERT_TRUE(job_.AwaitStep("lab", 2));
  // Reports every second for 12 s, as the store's slices do: a line every 5 s (the default).
  JobControl control(&registry_, op->id, "lab");
  for (int second = 1; second <= 12; ++second) {
    clock_.Advance(absl::Seconds(1));
    control.Progress(50 + second, 100);
  }
  job_.Open("lab", 2);
  AwaitDone(op->name);
  spdlog::drop(kDaemonLogger);
  const std::string text = log.str();
  size_t lines = 0;
  for (size_t at = text.find("states/s"); at != std::string::npos; at = text.find("states/s", at + 1)) ++lines;
  EXPECT_EQ(lines, 2u) << text;
  EXPECT_THAT(text, HasSubstr("update of map lab: 55/100 states (55%)"));
  EXPECT_THAT(text, HasSubstr("update of map lab: 60/100 states (60%)"));
}

TEST_F(OperationsTest, UpdatesOfDifferentMapsQueueOnOneThread) {
  auto a = registry_.StartUpdate("a", "RunUpdate");
  ASSERT_TRUE(job_.AwaitStep("a", 1));
  auto b = registry_.StartUpdate("b", "RunUpdate");
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NE(a->name, b->name);
  EXPECT_EQ(registry_.Get(b->name)->stage, OperationStage::kQueued);
  EXPECT_EQ(registry_.running(), 2u);
  job_.Open("a", 2);
  AwaitDone(a->name);
  ASSERT_TRUE(job_.AwaitStep("b", 1));
  job_.Open("b", 2);
  EXPECT_TRUE(AwaitDone(b->name).error.ok());
}

TEST_F(OperationsTest, CancelQueuedEndsItAtOnce) {
  auto a = registry_.StartUpdate("a", "RunUpdate");
  ASSERT_TRUE(job_.AwaitStep("a", 1));
  auto b = registry_.StartUpdate("b", "RunUpdate");
  ASSERT_TRUE(b.ok());
  auto cancelled = registry_.Cancel(b->name);
  ASSERT_TRUE(cancelled.ok());
  EXPECT_TRUE(cancelled->done());
  EXPECT_TRUE(cancelled->cancel_requested);
  EXPECT_EQ(cancelled->error.code(), absl::StatusCode::kCancelled);
  EXPECT_EQ(registry_.running(), 1u);
  job_.Open("a", 2);
  AwaitDone(a->name);
  EXPECT_EQ(job_.runs("b"), 0);
  // Cancelling what is done answers it unchanged.
  auto again = registry_.Cancel(b->name);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->error.code(), absl::StatusCode::kCancelled);
}

TEST_F(OperationsTest, CancelBeforePublishingStopsIt) {
  auto op = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(job_.AwaitStep("lab", 1));
  auto cancelling = registry_.Cancel(op->name);
  ASSERT_TRUE(cancelling.ok());
  EXPECT_FALSE(cancelling->done());
  EXPECT_TRUE(cancelling->cancel_requested);
  EXPECT_THAT(cancelling->message, HasSubstr("before it publishes"));
  job_.Open("lab", 2);
  const OperationView done = AwaitDone(op->name);
  EXPECT_EQ(done.error.code(), absl::StatusCode::kCancelled);
  EXPECT_FALSE(done.result.has_value());
}

TEST_F(OperationsTest, CancelWhilePublishingLetsItFinish) {
  auto op = registry_.StartUpdate("lab", "RunUpdate");
  ASSERT_TRUE(job_.AwaitStep("lab", 1));
  job_.Open("lab", 1);
  ASSERT_TRUE(job_.AwaitStep("lab", 2));
  auto refused = registry_.Cancel(op->name);
  ASSERT_TRUE(refused.ok());
  EXPECT_FALSE(refused->done());
  EXPECT_TRUE(refused->cancel_requested);
  EXPECT_THAT(refused->message, HasSubstr("cannot cancel"));
  EXPECT_THAT(refused->message, HasSubstr("log"));
  job_.Open("lab", 2);
  const OperationView done = AwaitDone(op->name);
  EXPECT_TRUE(done.error.ok());
  ASSERT_TRUE(done.result.has_value());
  EXPECT_THAT(done.message, HasSubstr("publishing"));
}

TEST_F(OperationsTest, JobErrorEndsTheOperation) {
  auto op = registry_.StartUpdate("broken", "RunUpdate");
  ASSERT_TRUE(op.ok());
  const OperationView done = AwaitDone(op->name);
  EXPECT_EQ(done.error.code(), absl::StatusCode::kInternal);
  EXPECT_EQ(done.message, "disk on fire");
  EXPECT_FALSE(done.result.has_value());
}

TEST_F(OperationsTest, UnknownNamesAreNotFound) {
  EXPECT_EQ(registry_.Get("operations/update-lab-9").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(registry_.Cancel("operations/update-lab-9").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(OperationsTest, ListNewestFirstByMapAndPages) {
  for (const char* map : {"a", "b", "a", "broken", "a"}) {
    job_.Open(map, 2);  // no stops
    auto op = registry_.StartUpdate(map, "RunUpdate");
    ASSERT_TRUE(op.ok());
    AwaitDone(op->name);
  }
  auto all = registry_.List("", false, 10, "");
  ASSERT_TRUE(all.ok());
  std::vector<std::string> names;
  for (const auto& op : all->operations) names.push_back(op.name);
  EXPECT_THAT(names, ElementsAre("operations/update-a-5", "operations/update-broken-4", "operations/update-a-3",
                                 "operations/update-b-2", "operations/update-a-1"));
  EXPECT_TRUE(all->next_page_token.empty());

  std::vector<std::string> paged;
  std::string token;
  do {
    auto page = registry_.List("a", false, 2, token);
    ASSERT_TRUE(page.ok());
    EXPECT_LE(page->operations.size(), 2u);
    for (const auto& op : page->operations) paged.push_back(op.name);
    token = page->next_page_token;
  } while (!token.empty());
  EXPECT_THAT(paged, ElementsAre("operations/update-a-5", "operations/update-a-3", "operations/update-a-1"));

  auto running = registry_.List("", true, 10, "");
  ASSERT_TRUE(running.ok());
  EXPECT_TRUE(running->operations.empty());
  EXPECT_EQ(registry_.List("", false, 10, "x").status().code(), absl::StatusCode::kInvalidArgument);

  const std::vector<OperationView> last = registry_.LastUpdates();
  ASSERT_EQ(last.size(), 3u);
  EXPECT_EQ(last[0].name, "operations/update-a-5");
  EXPECT_EQ(last[1].name, "operations/update-b-2");
  EXPECT_EQ(last[2].name, "operations/update-broken-4");
}

TEST(OperationsRetentionTest, FinishedOperationsAreBounded) {
  FakeClock clock(absl::FromUnixSeconds(1'700'000'000));
  OperationRegistry::Options options;
  options.max_finished = 2;
  options.keep_finished = absl::Hours(1);
  // A job that ends at once needs no gates.
  OperationRegistry registry([](JobControl&) -> absl::StatusOr<UpdateFigures> { return UpdateFigures(); }, clock,
                             options);
  const auto run = [&](const std::string& map) {
    auto op = registry.StartUpdate(map, "RunUpdate");
    EXPECT_TRUE(op.ok());
    const auto deadline = std::chrono::steady_clock::now() + kTimeout;
    while (!registry.Get(op->name)->done() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::yield();
    }
    return op->name;
  };
  const std::string first = run("a"), second = run("b"), third = run("c");
  run("d");  // starting it drops the oldest finished beyond two
  EXPECT_EQ(registry.Get(first).status().code(), absl::StatusCode::kNotFound);
  EXPECT_TRUE(registry.Get(second).ok());
  EXPECT_TRUE(registry.Get(third).ok());
  clock.Advance(absl::Hours(2));
  const std::string fifth = run("e");  // b, c and d are now older than an hour
  EXPECT_EQ(registry.Get(third).status().code(), absl::StatusCode::kNotFound);
  EXPECT_TRUE(registry.Get(fifth).ok());
  EXPECT_EQ(registry.List("", false, 10, "")->operations.size(), 1u);
}

TEST_F(OperationsTest, StopCancelsQueuedAndRefusesNew) {
  auto a = registry_.StartUpdate("a", "RunUpdate");
  ASSERT_TRUE(job_.AwaitStep("a", 1));
  auto b = registry_.StartUpdate("b", "RunUpdate");
  ASSERT_TRUE(b.ok());
  job_.Open("a", 2);  // the running job reaches BeginPublishing after Stop or before: either way it ends
  registry_.Stop();
  EXPECT_EQ(registry_.Get(b->name)->error.code(), absl::StatusCode::kCancelled);
  EXPECT_TRUE(registry_.Get(a->name)->done());
  EXPECT_EQ(registry_.StartUpdate("c", "RunUpdate").status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(registry_.running(), 0u);
}

TEST_F(OperationsTest, StopBeforePublishingCancelsTheRunningJob) {
  auto a = registry_.StartUpdate("a", "RunUpdate");
  ASSERT_TRUE(job_.AwaitStep("a", 1));
  std::thread stopper([&] { registry_.Stop(); });
  // Stop waits for the job; the job reaches BeginPublishing only once the gate opens, after Stop
  // has marked the registry stopping (StartUpdate refuses from then on).
  while (registry_.StartUpdate("probe", "RunUpdate").ok()) std::this_thread::yield();
  job_.Open("a", 2);
  stopper.join();
  EXPECT_EQ(registry_.Get(a->name)->error.code(), absl::StatusCode::kCancelled);
}

}  // namespace
}  // namespace fremen::server
