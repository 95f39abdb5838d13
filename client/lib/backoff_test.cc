#include "client/lib/backoff.h"

#include <gtest/gtest.h>

namespace fremen::client {
namespace {

RetryPolicy Policy(double jitter) {
  RetryPolicy policy;
  policy.initial_backoff = absl::Milliseconds(100);
  policy.max_backoff = absl::Seconds(2);
  policy.multiplier = 2;
  policy.jitter = jitter;
  return policy;
}

TEST(BackoffTest, DoublesFromTheInitialDelayUpToTheCap) {
  Backoff backoff(Policy(0), 1);
  const absl::Duration expected[] = {absl::Milliseconds(100), absl::Milliseconds(200), absl::Milliseconds(400),
                                     absl::Milliseconds(800), absl::Milliseconds(1600), absl::Seconds(2),
                                     absl::Seconds(2)};
  for (absl::Duration want : expected) EXPECT_EQ(backoff.Next(), want);
  EXPECT_EQ(backoff.retries(), 7);
}

TEST(BackoffTest, ResetStartsAgainFromTheInitialDelay) {
  Backoff backoff(Policy(0), 1);
  backoff.Next();
  backoff.Next();
  backoff.Reset();
  EXPECT_EQ(backoff.retries(), 0);
  EXPECT_EQ(backoff.Next(), absl::Milliseconds(100));
}

TEST(BackoffTest, JitterStaysWithinItsBoundsAndVaries) {
  Backoff backoff(Policy(0.2), 42);
  absl::Duration first = backoff.Next();
  EXPECT_GE(first, absl::Milliseconds(80));
  EXPECT_LE(first, absl::Milliseconds(120));
  bool varied = false;
  for (int i = 0; i < 20; ++i) {
    backoff.Reset();
    const absl::Duration d = backoff.Next();
    EXPECT_GE(d, absl::Milliseconds(80));
    EXPECT_LE(d, absl::Milliseconds(120));
    varied |= d != first;
  }
  EXPECT_TRUE(varied) << "jitter never changed the delay";
}

TEST(BackoffTest, NominalDoesNotOverflowAfterManyRetries) {
  EXPECT_EQ(Backoff::Nominal(Policy(0), 10000), absl::Seconds(2));
}

TEST(BackoffTest, MaxAttemptsCountsTheFirstAttempt) {
  RetryPolicy policy = Policy(0);
  policy.max_attempts = 3;
  Backoff backoff(policy, 1);
  EXPECT_TRUE(backoff.MayRetry());  // attempt 2
  backoff.Next();
  EXPECT_TRUE(backoff.MayRetry());  // attempt 3
  backoff.Next();
  EXPECT_FALSE(backoff.MayRetry());
  policy.max_attempts = 0;
  Backoff unbounded(policy, 1);
  for (int i = 0; i < 100; ++i) unbounded.Next();
  EXPECT_TRUE(unbounded.MayRetry());
}

}  // namespace
}  // namespace fremen::client
