// The delays between retries of a RetryPolicy: initial, ×multiplier per attempt, capped at
// max_backoff, each with random jitter. Pure logic, so that the schedule is unit-tested.
// Thread-compatible: one retry loop owns one Backoff.
#pragma once

#include <cstdint>
#include <random>

#include "absl/time/time.h"
#include "client/lib/options.h"

namespace fremen::client {

class Backoff {
 public:
  // `seed` makes the jitter reproducible in tests; clients seed from a random device.
  explicit Backoff(const RetryPolicy& policy, uint64_t seed);

  // The delay before the next retry; counts the retry.
  absl::Duration Next();
  // After a success: the next failure starts again from initial_backoff.
  void Reset() { retries_ = 0; }
  // Retries counted since construction or the last Reset.
  int retries() const { return retries_; }
  // Whether another attempt is allowed after `retries()` retries (max_attempts; 0 = unbounded).
  bool MayRetry() const { return policy_.max_attempts <= 0 || retries_ + 1 < policy_.max_attempts; }

  // The delay before retry `retry` (0-based) without jitter.
  static absl::Duration Nominal(const RetryPolicy& policy, int retry);

 private:
  RetryPolicy policy_;
  std::mt19937_64 random_;
  int retries_ = 0;
};

}  // namespace fremen::client
