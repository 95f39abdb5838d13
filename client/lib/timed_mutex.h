// A mutex that can be waited for with a time limit, in a form clang's thread-safety analysis
// understands (absl/base/thread_annotations.h): absl::Mutex has no timed lock (LockWhenWithTimeout
// acquires it in the end either way), and libstdc++'s std::timed_mutex carries no annotations.
// Thread-safety: a mutex.
#pragma once

#include <mutex>

#include "absl/base/thread_annotations.h"
#include "absl/time/time.h"

namespace fremen::client {

class ABSL_LOCKABLE TimedMutex {
 public:
  void Lock() ABSL_EXCLUSIVE_LOCK_FUNCTION() { mutex_.lock(); }
  void Unlock() ABSL_UNLOCK_FUNCTION() { mutex_.unlock(); }
  // Whether it was locked within `timeout`.
  bool TryLockFor(absl::Duration timeout) ABSL_EXCLUSIVE_TRYLOCK_FUNCTION(true) {
    return mutex_.try_lock_for(absl::ToChronoNanoseconds(timeout));
  }

 private:
  std::timed_mutex mutex_;
};

// Holds a TimedMutex for its scope, as absl::MutexLock holds an absl::Mutex.
class ABSL_SCOPED_LOCKABLE TimedMutexLock {
 public:
  explicit TimedMutexLock(TimedMutex* mutex) ABSL_EXCLUSIVE_LOCK_FUNCTION(mutex) : mutex_(mutex) { mutex_->Lock(); }
  ~TimedMutexLock() ABSL_UNLOCK_FUNCTION() { mutex_->Unlock(); }
  TimedMutexLock(const TimedMutexLock&) = delete;
  TimedMutexLock& operator=(const TimedMutexLock&) = delete;

 private:
  TimedMutex* const mutex_;
};

}  // namespace fremen::client
