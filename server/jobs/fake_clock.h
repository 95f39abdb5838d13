// A clock for tests: time stands still until the test moves it (Set, Advance), and a thread
// waiting in WaitUntil is woken then — so a scheduler thread runs against a fake clock without a
// single sleep. AwaitWaiters lets the test know that the waiting threads have caught up with the
// time it set (they have re-checked and gone back to waiting).
//
// Why Advance takes each waiter's mutex before notifying it: the waiter holds that mutex from its
// registration until cv.wait releases it, so the notification cannot fall between the two and be
// lost (CondVar::Wait releases it atomically).
// Thread-safety: every method may be called from any thread; a clock must outlive its waiters.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "base/mutex.h"
#include "server/jobs/clock.h"

namespace fremen::server {

class FakeClock final : public Clock {
 public:
  explicit FakeClock(absl::Time now) : now_(now) {}

  absl::Time Now() const override ABSL_LOCKS_EXCLUDED(mutex_) {
    base::MutexLock lock(&mutex_);
    return now_;
  }

  void WaitUntil(base::CondVar& cv, base::Mutex& mu, absl::Time deadline) const override
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) ABSL_LOCKS_EXCLUDED(mutex_) {
    const Waiter self{&cv, &mu};
    {
      base::MutexLock guard(&mutex_);
      if (now_ >= deadline) return;
      waiters_.push_back(self);
      waiters_changed_.SignalAll();
    }
    cv.Wait(&mu);
    base::MutexLock guard(&mutex_);
    // Still listed after a wake-up that was not Advance's (Stop, a spurious one).
    if (auto it = std::find(waiters_.begin(), waiters_.end(), self); it != waiters_.end()) waiters_.erase(it);
    waiters_changed_.SignalAll();
  }

  void Set(absl::Time now) ABSL_LOCKS_EXCLUDED(mutex_) {
    std::vector<Waiter> woken;
    {
      base::MutexLock guard(&mutex_);
      now_ = now;
      woken.swap(waiters_);
      waiters_changed_.SignalAll();
    }
    for (const Waiter& w : woken) {
      base::MutexLock waiter_lock(w.mutex);
      w.cv->SignalAll();
    }
  }
  void Advance(absl::Duration d) { Set(Now() + d); }

  // Blocks until `n` threads wait in WaitUntil; false when that has not happened within `timeout`
  // (a stuck thread fails the test instead of hanging it).
  bool AwaitWaiters(size_t n, std::chrono::seconds timeout = std::chrono::seconds(30)) const
      ABSL_LOCKS_EXCLUDED(mutex_) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    base::MutexLock guard(&mutex_);
    while (waiters_.size() < n) {
      if (waiters_changed_.WaitUntil(&mutex_, deadline)) return waiters_.size() >= n;  // timed out
    }
    return true;
  }

 private:
  struct Waiter {
    base::CondVar* cv;
    base::Mutex* mutex;
    bool operator==(const Waiter&) const = default;
  };

  mutable base::Mutex mutex_;
  mutable base::CondVar waiters_changed_;  // AwaitWaiters
  absl::Time now_ ABSL_GUARDED_BY(mutex_);
  mutable std::vector<Waiter> waiters_ ABSL_GUARDED_BY(mutex_);
};

}  // namespace fremen::server
