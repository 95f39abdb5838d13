// The project's locks: std::mutex, std::shared_mutex and std::timed_mutex behind classes that
// carry clang's thread-safety annotations (absl/base/thread_annotations.h), as leveldb's
// port::Mutex does, so that members declared ABSL_GUARDED_BY a lock and helpers declared
// ABSL_EXCLUSIVE_LOCKS_REQUIRED it are checked by the compiler (`make thread-safety`).
//
// Why not absl::Mutex, which is annotated already: Debian's libabsl is not built with TSan, so
// TSan sees neither its locking nor its waking and reports every access it guards as a race. The
// locks here are the standard library's, which TSan intercepts (pthread), so TSan and the
// analysis both see the same locking. docs/performance.md ("Locks") says more.
//
// Waiting: CondVar waits on a Mutex the caller holds, as std::condition_variable does on a
// std::unique_lock, without a predicate — write the loop `while (!ready_) cv_.Wait(&mu_);` in the
// caller, where the analysis knows mu_ is held (it does not look into lambdas).
// Thread-safety: these are the locks.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <shared_mutex>

#include "absl/base/thread_annotations.h"
#include "absl/time/time.h"

namespace fremen::base {

class CondVar;

class ABSL_LOCKABLE Mutex {
 public:
  Mutex() = default;
  Mutex(const Mutex&) = delete;
  Mutex& operator=(const Mutex&) = delete;

  void Lock() ABSL_EXCLUSIVE_LOCK_FUNCTION() { mutex_.lock(); }
  void Unlock() ABSL_UNLOCK_FUNCTION() { mutex_.unlock(); }
  // Whether it was free (and is now the caller's).
  bool TryLock() ABSL_EXCLUSIVE_TRYLOCK_FUNCTION(true) { return mutex_.try_lock(); }
  // Tells the analysis that the caller holds the lock where it cannot see it taken (a callback run
  // under it); checks nothing at run time (std::mutex does not know its owner).
  void AssertHeld() const ABSL_ASSERT_EXCLUSIVE_LOCK() {}

 private:
  friend class CondVar;
  std::mutex mutex_;
};

// Readers share it, a writer holds it alone. std::shared_mutex's preference (glibc prefers readers)
// is kept: a lock whose writer must not starve stays something else (storage/lmdb/lmdb_env.h).
class ABSL_LOCKABLE SharedMutex {
 public:
  SharedMutex() = default;
  SharedMutex(const SharedMutex&) = delete;
  SharedMutex& operator=(const SharedMutex&) = delete;

  void Lock() ABSL_EXCLUSIVE_LOCK_FUNCTION() { mutex_.lock(); }
  void Unlock() ABSL_UNLOCK_FUNCTION() { mutex_.unlock(); }
  void ReaderLock() ABSL_SHARED_LOCK_FUNCTION() { mutex_.lock_shared(); }
  void ReaderUnlock() ABSL_UNLOCK_FUNCTION() { mutex_.unlock_shared(); }
  void AssertHeld() const ABSL_ASSERT_EXCLUSIVE_LOCK() {}
  void AssertReaderHeld() const ABSL_ASSERT_SHARED_LOCK() {}

 private:
  std::shared_mutex mutex_;
};

// A mutex whose Lock can give up after a while.
class ABSL_LOCKABLE TimedMutex {
 public:
  TimedMutex() = default;
  TimedMutex(const TimedMutex&) = delete;
  TimedMutex& operator=(const TimedMutex&) = delete;

  void Lock() ABSL_EXCLUSIVE_LOCK_FUNCTION() { mutex_.lock(); }
  void Unlock() ABSL_UNLOCK_FUNCTION() { mutex_.unlock(); }
  // Whether it was locked within `timeout`.
  template <class Rep, class Period>
  bool TryLockFor(const std::chrono::duration<Rep, Period>& timeout) ABSL_EXCLUSIVE_TRYLOCK_FUNCTION(true) {
    return mutex_.try_lock_for(timeout);
  }

 private:
  std::timed_mutex mutex_;
};

// Holds a lock exclusively for its scope (waiting as long as it takes): MutexLock,
// TimedMutexLock and WriterMutexLock below.
template <class Lockable>
class ABSL_SCOPED_LOCKABLE ExclusiveLock {
 public:
  explicit ExclusiveLock(Lockable* mutex) ABSL_EXCLUSIVE_LOCK_FUNCTION(mutex) : mutex_(mutex) { mutex->Lock(); }
  ~ExclusiveLock() ABSL_UNLOCK_FUNCTION() { mutex_->Unlock(); }
  ExclusiveLock(const ExclusiveLock&) = delete;
  ExclusiveLock& operator=(const ExclusiveLock&) = delete;

 private:
  Lockable* const mutex_;
};

using MutexLock = ExclusiveLock<Mutex>;
using TimedMutexLock = ExclusiveLock<TimedMutex>;
using WriterMutexLock = ExclusiveLock<SharedMutex>;

// A MutexLock that can be let go before its scope ends (Release), for a branch that must run
// unlocked.
class ABSL_SCOPED_LOCKABLE ReleasableMutexLock {
 public:
  explicit ReleasableMutexLock(Mutex* mutex) ABSL_EXCLUSIVE_LOCK_FUNCTION(mutex) : mutex_(mutex) { mutex->Lock(); }
  ~ReleasableMutexLock() ABSL_UNLOCK_FUNCTION() {
    if (mutex_ != nullptr) mutex_->Unlock();
  }
  void Release() ABSL_UNLOCK_FUNCTION() {
    mutex_->Unlock();
    mutex_ = nullptr;
  }
  ReleasableMutexLock(const ReleasableMutexLock&) = delete;
  ReleasableMutexLock& operator=(const ReleasableMutexLock&) = delete;

 private:
  Mutex* mutex_;
};

// Holds a SharedMutex shared for its scope.
class ABSL_SCOPED_LOCKABLE ReaderMutexLock {
 public:
  explicit ReaderMutexLock(SharedMutex* mutex) ABSL_SHARED_LOCK_FUNCTION(mutex) : mutex_(mutex) {
    mutex->ReaderLock();
  }
  ~ReaderMutexLock() ABSL_UNLOCK_FUNCTION() { mutex_->ReaderUnlock(); }
  ReaderMutexLock(const ReaderMutexLock&) = delete;
  ReaderMutexLock& operator=(const ReaderMutexLock&) = delete;

 private:
  SharedMutex* const mutex_;
};

// A condition variable over a Mutex: every wait releases the caller's lock while it sleeps and
// holds it again when it returns (also after a spurious wake-up: wait in a loop).
class CondVar {
 public:
  CondVar() = default;
  CondVar(const CondVar&) = delete;
  CondVar& operator=(const CondVar&) = delete;

  void Wait(Mutex* mutex) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex) {
    std::unique_lock<std::mutex> lock(mutex->mutex_, std::adopt_lock);
    cv_.wait(lock);
    lock.release();  // the caller's lock again, not this scope's
  }
  // Waits until `deadline` at the latest (on the deadline's clock). Returns whether the deadline
  // passed (false: woken before it).
  template <class Clock, class Duration>
  bool WaitUntil(Mutex* mutex, const std::chrono::time_point<Clock, Duration>& deadline)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex) {
    std::unique_lock<std::mutex> lock(mutex->mutex_, std::adopt_lock);
    const bool timed_out = cv_.wait_until(lock, deadline) == std::cv_status::timeout;
    lock.release();
    return timed_out;
  }
  // WaitUntil for an absl::Time, on the wall clock (system_clock: glibc waits on CLOCK_REALTIME);
  // absl::InfiniteFuture(): no limit.
  bool WaitWithDeadline(Mutex* mutex, absl::Time deadline) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex) {
    if (deadline == absl::InfiniteFuture()) {
      Wait(mutex);
      return false;
    }
    return WaitUntil(mutex, absl::ToChronoTime(deadline));
  }
  // Waits `timeout` at most (steady clock). Returns whether it passed.
  template <class Rep, class Period>
  bool WaitFor(Mutex* mutex, const std::chrono::duration<Rep, Period>& timeout) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex) {
    return WaitUntil(mutex, std::chrono::steady_clock::now() + timeout);
  }

  void Signal() { cv_.notify_one(); }
  void SignalAll() { cv_.notify_all(); }

 private:
  std::condition_variable cv_;
};

}  // namespace fremen::base
