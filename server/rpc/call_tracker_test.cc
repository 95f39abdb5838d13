#include "server/rpc/call_tracker.h"

#include <gtest/gtest.h>

#include <memory>
#include <thread>

namespace fremen::server {
namespace {

TEST(CallTrackerTest, DrainWaitsForCallsInFlight) {
  CallTracker calls;
  ASSERT_TRUE(calls.Begin().ok());
  // The call ends only once draining has begun (Begin is refused from then on), so a Drain that
  // did not wait would find it in flight and return 1.
  std::thread finisher([&] {
    while (calls.Begin().ok()) calls.End();
    calls.End();
  });
  EXPECT_EQ(calls.Drain(absl::Seconds(30)), 0);
  finisher.join();
}

TEST(CallTrackerTest, DrainGivesUpAfterTheTimeout) {
  CallTracker calls;
  ASSERT_TRUE(calls.Begin().ok());
  EXPECT_EQ(calls.Drain(absl::Milliseconds(10)), 1);
  calls.End();
}

TEST(CallTrackerTest, NewCallsAreRefusedWhileDraining) {
  CallTracker calls;
  EXPECT_EQ(calls.Drain(absl::ZeroDuration()), 0);
  EXPECT_EQ(calls.Begin().code(), absl::StatusCode::kUnavailable);
}

// A stream that ends its call when told to wind down, as an ingest stream does.
class FakeStream final : public CallTracker::Drainable {
 public:
  explicit FakeStream(CallTracker& calls) : calls_(calls) {}
  void Begin(std::weak_ptr<Drainable> self) {
    auto id = calls_.BeginStream(std::move(self));
    ASSERT_TRUE(id.ok());
    id_ = *id;
  }
  void WindDown() override {
    ++wound_down;
    calls_.EndStream(id_);
  }
  int wound_down = 0;

 private:
  CallTracker& calls_;
  uint64_t id_ = 0;
};

TEST(CallTrackerTest, DrainWindsStreamsDownAndDoesNotWaitForThem) {
  CallTracker calls;
  auto stream = std::make_shared<FakeStream>(calls);
  stream->Begin(stream);
  EXPECT_EQ(calls.Drain(absl::Seconds(30)), 0);
  EXPECT_EQ(stream->wound_down, 1);
  EXPECT_EQ(calls.BeginStream(stream).status().code(), absl::StatusCode::kUnavailable);
}

TEST(CallTrackerTest, EndedOrDeletedStreamsAreNotWoundDown) {
  CallTracker calls;
  auto ended = std::make_shared<FakeStream>(calls);
  ended->Begin(ended);
  ended->WindDown();  // ends its call
  auto gone = std::make_shared<FakeStream>(calls);
  gone->Begin(gone);
  gone.reset();  // still counted in flight, but nothing to wind down
  EXPECT_EQ(calls.Drain(absl::Milliseconds(10)), 1);
  EXPECT_EQ(ended->wound_down, 1);
  calls.End();
}

}  // namespace
}  // namespace fremen::server
