#include "base/mutex.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "absl/time/clock.h"

namespace fremen::base {
namespace {

// What the tests share between threads, guarded as production code declares it.
struct Counter {
  Mutex mutex;
  int count ABSL_GUARDED_BY(mutex) = 0;
};

struct SharedCounter {
  SharedMutex mutex;
  int count ABSL_GUARDED_BY(mutex) = 0;
};

struct Flag {
  Mutex mutex;
  CondVar changed;
  bool ready ABSL_GUARDED_BY(mutex) = false;
};

// Four threads add to the counter under Lock; what it holds at the end. Exact when Lock excludes
// the others (and TSan, which sees the std::mutex underneath, finds no race in the sanitizer builds).
template <class Lock, class Guarded>
int CountFromFourThreads(Guarded& counter) {
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 10000; ++i) {
        Lock lock(&counter.mutex);
        ++counter.count;
      }
    });
  }
  for (std::thread& t : threads) t.join();
  Lock lock(&counter.mutex);
  return counter.count;
}

TEST(MutexTest, MutexLockSerialisesWriters) {
  Counter counter;
  EXPECT_EQ(CountFromFourThreads<MutexLock>(counter), 40000);
}

TEST(MutexTest, ReleasableMutexLockUnlocksOnRelease) {
  Mutex mutex;
  {
    ReleasableMutexLock lock(&mutex);
    lock.Release();
    // Released: another thread can take the lock while this scope is still open.
    std::thread other([&] { MutexLock taken(&mutex); });
    other.join();
  }
  MutexLock again(&mutex);  // and the scope's end did not unlock it a second time
}

TEST(SharedMutexTest, ReadersShareWritersExclude) {
  SharedCounter counter;
  {
    ReaderMutexLock first(&counter.mutex);
    // A second reader gets in while the first holds it.
    std::thread reader([&] { ReaderMutexLock second(&counter.mutex); });
    reader.join();
  }
  EXPECT_EQ(CountFromFourThreads<WriterMutexLock>(counter), 40000);
}

TEST(TimedMutexTest, TryLockForGivesUpWhileHeldElsewhere) {
  TimedMutex mutex;
  bool locked_meanwhile = false;
  {
    TimedMutexLock held(&mutex);
    std::thread other([&] {
      if (mutex.TryLockFor(std::chrono::milliseconds(1))) {
        locked_meanwhile = true;
        mutex.Unlock();
      }
    });
    other.join();
  }
  EXPECT_FALSE(locked_meanwhile);
  bool locked_once_free = false;
  if (mutex.TryLockFor(std::chrono::seconds(0))) {
    locked_once_free = true;
    mutex.Unlock();
  }
  EXPECT_TRUE(locked_once_free);
}

// The waiter sleeps with the lock released (the signaller takes it) and wakes holding it.
TEST(CondVarTest, WaitReleasesTheLockAndHoldsItAgain) {
  Flag flag;
  std::thread signaller([&] {
    MutexLock lock(&flag.mutex);  // taken while the waiter sleeps
    flag.ready = true;
    flag.changed.SignalAll();
  });
  bool held_after_wait = false;
  {
    MutexLock lock(&flag.mutex);
    while (!flag.ready) flag.changed.Wait(&flag.mutex);
    // Held again: no other thread can take it now.
    std::thread probe([&] {
      if (flag.mutex.TryLock()) {
        flag.mutex.Unlock();
      } else {
        held_after_wait = true;
      }
    });
    probe.join();
  }
  signaller.join();
  EXPECT_TRUE(held_after_wait);
}

TEST(CondVarTest, WaitForAndWaitUntilTimeOutWithoutASignal) {
  Mutex mutex;
  CondVar never;
  MutexLock lock(&mutex);
  // Spurious wake-ups may end a wait early (false), but with no signal at all some wait times out.
  bool timed_out = false;
  for (int i = 0; i < 100 && !timed_out; ++i) timed_out = never.WaitFor(&mutex, std::chrono::milliseconds(1));
  EXPECT_TRUE(timed_out);
  timed_out = false;
  for (int i = 0; i < 100 && !timed_out; ++i) {
    timed_out = never.WaitUntil(&mutex, std::chrono::system_clock::now() + std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(timed_out);
  timed_out = false;
  for (int i = 0; i < 100 && !timed_out; ++i) {
    timed_out = never.WaitWithDeadline(&mutex, absl::Now() + absl::Milliseconds(1));
  }
  EXPECT_TRUE(timed_out);
}

// Another thread sets the flag and signals; `wait(flag)` waits once with the lock held and
// returns whether it timed out. Whether any wait timed out before the flag was seen.
template <class Wait>
bool TimedOutBeforeTheSignal(Wait wait) {
  Flag flag;
  std::thread signaller([&] {
    MutexLock lock(&flag.mutex);
    flag.ready = true;
    flag.changed.Signal();
  });
  bool timed_out = false;
  {
    MutexLock lock(&flag.mutex);
    while (!flag.ready && !timed_out) timed_out = wait(flag);
  }
  signaller.join();
  return timed_out;
}

// absl::InfiniteFuture() sets no limit: only the signal ends the wait.
TEST(CondVarTest, WaitWithDeadlineInfiniteFutureWaitsForTheSignal) {
  EXPECT_FALSE(TimedOutBeforeTheSignal([](Flag& flag) ABSL_NO_THREAD_SAFETY_ANALYSIS {  // called holding flag.mutex
    return flag.changed.WaitWithDeadline(&flag.mutex, absl::InfiniteFuture());
  }));
}

// A far deadline: the loop ends by the signal, never by time.
TEST(CondVarTest, WaitUntilReportsASignalBeforeTheDeadline) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::hours(1);
  EXPECT_FALSE(TimedOutBeforeTheSignal([deadline](Flag& flag) ABSL_NO_THREAD_SAFETY_ANALYSIS {  // likewise
    return flag.changed.WaitUntil(&flag.mutex, deadline);
  }));
}

}  // namespace
}  // namespace fremen::base
