// A clock for tests: time stands still until the test moves it (Set, Advance), and a thread
// waiting in WaitUntil is woken then — so a scheduler thread runs against a fake clock without a
// single sleep. AwaitWaiters lets the test know that the waiting threads have caught up with the
// time it set (they have re-checked and gone back to waiting).
//
// Why Advance takes each waiter's mutex before notifying it: the waiter holds that mutex from its
// registration until cv.wait releases it, so the notification cannot fall between the two and be
// lost.
// Thread-safety: every method may be called from any thread; a clock must outlive its waiters.
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "server/clock.h"

namespace fremen::server {

class FakeClock final : public Clock {
 public:
  explicit FakeClock(absl::Time now) : now_(now) {}

  absl::Time Now() const override {
    std::lock_guard lock(mutex_);
    return now_;
  }

  void WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock,
                 absl::Time deadline) const override {
    const Waiter self{&cv, lock.mutex()};
    {
      std::lock_guard guard(mutex_);
      if (now_ >= deadline) return;
      waiters_.push_back(self);
      waiters_changed_.notify_all();
    }
    cv.wait(lock);
    std::lock_guard guard(mutex_);
    // Still listed after a wake-up that was not Advance's (Stop, a spurious one).
    if (auto it = std::find(waiters_.begin(), waiters_.end(), self); it != waiters_.end()) waiters_.erase(it);
    waiters_changed_.notify_all();
  }

  void Set(absl::Time now) {
    std::vector<Waiter> woken;
    {
      std::lock_guard guard(mutex_);
      now_ = now;
      woken.swap(waiters_);
      waiters_changed_.notify_all();
    }
    for (const Waiter& w : woken) {
      std::lock_guard waiter_lock(*w.mutex);
      w.cv->notify_all();
    }
  }
  void Advance(absl::Duration d) { Set(Now() + d); }

  // Blocks until `n` threads wait in WaitUntil; false when that has not happened within `timeout`
  // (a stuck thread fails the test instead of hanging it).
  bool AwaitWaiters(size_t n, std::chrono::seconds timeout = std::chrono::seconds(30)) const {
    std::unique_lock guard(mutex_);
    return waiters_changed_.wait_for(guard, timeout, [&] { return waiters_.size() >= n; });
  }

 private:
  struct Waiter {
    std::condition_variable* cv;
    std::mutex* mutex;
    bool operator==(const Waiter&) const = default;
  };

  mutable std::mutex mutex_;
  mutable std::condition_variable waiters_changed_;
  absl::Time now_;
  mutable std::vector<Waiter> waiters_;
};

}  // namespace fremen::server
