// A clock for tests: time stands still until the test moves it (Set, Advance), and a thread
// waiting in WaitUntil is woken then — so a scheduler thread runs against a fake clock without a
// single sleep. AwaitWaiters lets the test know that the waiting threads have caught up with the
// time it set (they have re-checked and gone back to waiting).
//
// Why Advance takes each waiter's mutex before notifying it: the waiter holds that mutex from its
// registration until cv.wait releases it, so the notification cannot fall between the two and be
// lost (absl::CondVar::Wait releases it atomically).
// Thread-safety: every method may be called from any thread; a clock must outlive its waiters.
#pragma once

#include <algorithm>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "server/clock.h"

namespace fremen::server {

class FakeClock final : public Clock {
 public:
  explicit FakeClock(absl::Time now) : now_(now) {}

  absl::Time Now() const override ABSL_LOCKS_EXCLUDED(mutex_) {
    absl::MutexLock lock(&mutex_);
    return now_;
  }

  void WaitUntil(absl::CondVar& cv, absl::Mutex& mu, absl::Time deadline) const override
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) ABSL_LOCKS_EXCLUDED(mutex_) {
    const Waiter self{&cv, &mu};
    {
      absl::MutexLock guard(&mutex_);
      if (now_ >= deadline) return;
      waiters_.push_back(self);
    }
    cv.Wait(&mu);
    absl::MutexLock guard(&mutex_);
    // Still listed after a wake-up that was not Advance's (Stop, a spurious one).
    if (auto it = std::find(waiters_.begin(), waiters_.end(), self); it != waiters_.end()) waiters_.erase(it);
  }

  void Set(absl::Time now) ABSL_LOCKS_EXCLUDED(mutex_) {
    std::vector<Waiter> woken;
    {
      absl::MutexLock guard(&mutex_);
      now_ = now;
      woken.swap(waiters_);
    }
    for (const Waiter& w : woken) {
      absl::MutexLock waiter_lock(w.mutex);
      w.cv->SignalAll();
    }
  }
  void Advance(absl::Duration d) { Set(Now() + d); }

  // Blocks until `n` threads wait in WaitUntil; false when that has not happened within `timeout`
  // (a stuck thread fails the test instead of hanging it).
  bool AwaitWaiters(size_t n, absl::Duration timeout = absl::Seconds(30)) const ABSL_LOCKS_EXCLUDED(mutex_) {
    struct Enough {
      const FakeClock* clock;
      size_t n;
      bool operator()() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(clock->mutex_) { return clock->waiters_.size() >= n; }
    } enough{this, n};
    absl::MutexLock guard(&mutex_);
    return mutex_.AwaitWithTimeout(absl::Condition(&enough), timeout);
  }

 private:
  struct Waiter {
    absl::CondVar* cv;
    absl::Mutex* mutex;
    bool operator==(const Waiter&) const = default;
  };

  // The waiters' count is waited for with Mutex::AwaitWithTimeout, which re-checks it whenever the
  // mutex is released: no condition variable of its own.
  mutable absl::Mutex mutex_;
  absl::Time now_ ABSL_GUARDED_BY(mutex_);
  mutable std::vector<Waiter> waiters_ ABSL_GUARDED_BY(mutex_);
};

}  // namespace fremen::server
