// Time as the update machinery sees it: the wall clock in the daemon, a fake one in tests
// (server/jobs/fake_clock.h), so that schedules — time zones, daylight-saving jumps, days without a
// run — and operation timestamps are tested without sleeping.
//
// WaitUntil is the one way a thread waits for a time: the real clock waits on the condition
// variable with a wall-clock deadline; the fake clock wakes the waiter when a test moves time on.
// Thread-safety: implementations may be used from any thread.
#pragma once

#include "absl/base/thread_annotations.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "base/mutex.h"

namespace fremen::server {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual absl::Time Now() const = 0;
  // Waits on `cv` (releasing `mu`, as cv.Wait does) until it is notified or Now() reaches
  // `deadline` (InfiniteFuture: only a notification ends the wait). May return early: callers
  // re-check what they wait for, as with any condition variable.
  virtual void WaitUntil(base::CondVar& cv, base::Mutex& mu, absl::Time deadline) const
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) = 0;
};

// The wall clock. A deadline is a wall-clock time, so a clock stepped by NTP or a machine that
// slept still wakes the waiter at the right local time (CondVar::WaitWithDeadline waits on
// CLOCK_REALTIME).
class RealClock final : public Clock {
 public:
  absl::Time Now() const override { return absl::Now(); }
  void WaitUntil(base::CondVar& cv, base::Mutex& mu, absl::Time deadline) const override
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    cv.WaitWithDeadline(&mu, deadline);
  }

  // The one instance the daemon uses.
  static const RealClock& Get() {
    static const RealClock clock;
    return clock;
  }
};

}  // namespace fremen::server
