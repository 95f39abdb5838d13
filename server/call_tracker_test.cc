#include "server/call_tracker.h"

#include <gtest/gtest.h>

#include <thread>

namespace fremen::server {
namespace {

TEST(CallTrackerTest, DrainWaitsForCallsInFlight) {
  CallTracker calls;
  ASSERT_TRUE(calls.Begin().ok());
  std::thread finisher([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
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

}  // namespace
}  // namespace fremen::server
