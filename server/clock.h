// Time as the update machinery sees it: the wall clock in the daemon, a fake one in tests
// (server/fake_clock.h), so that schedules — time zones, daylight-saving jumps, days without a
// run — and operation timestamps are tested without sleeping.
//
// WaitUntil is the one way a thread waits for a time: the real clock waits on the condition
// variable with a wall-clock deadline; the fake clock wakes the waiter when a test moves time on.
// Thread-safety: implementations may be used from any thread.
#pragma once

#include <condition_variable>
#include <mutex>

#include "absl/time/clock.h"
#include "absl/time/time.h"

namespace fremen::server {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual absl::Time Now() const = 0;
  // Waits on `cv` (`lock` held, as for cv.wait) until it is notified or Now() reaches `deadline`
  // (InfiniteFuture: only a notification ends the wait). May return early: callers re-check what
  // they wait for, as with any condition variable.
  virtual void WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock,
                         absl::Time deadline) const = 0;
};

// The wall clock. A deadline is a wall-clock time, so a clock stepped by NTP or a machine that
// slept still wakes the waiter at the right local time (glibc waits on CLOCK_REALTIME for
// system_clock deadlines).
class RealClock final : public Clock {
 public:
  absl::Time Now() const override { return absl::Now(); }
  void WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock,
                 absl::Time deadline) const override {
    if (deadline == absl::InfiniteFuture()) {
      cv.wait(lock);
    } else {
      cv.wait_until(lock, absl::ToChronoTime(deadline));
    }
  }

  // The one instance the daemon uses.
  static const RealClock& Get() {
    static const RealClock clock;
    return clock;
  }
};

}  // namespace fremen::server
