#include "storage/parallel_shards.h"

#include <algorithm>
#include <atomic>
#include <deque>
#include <thread>

#include "absl/base/thread_annotations.h"
#include "base/mutex.h"

namespace fremen::storage {

namespace {

// One ParallelForShards call: its shards are claimed one at a time, by the caller and by the
// helpers that took one of its tickets, until none is left.
struct Job {
  const std::function<void(size_t)>* f;
  size_t shards;
  std::atomic<size_t> next{1};  // shard 0 is the caller's
  size_t holders = 0;           // helpers inside the job; under HelperPool::mutex_

  // Runs the shards left, one claim at a time.
  void RunClaims() {
    for (size_t s = next.fetch_add(1); s < shards; s = next.fetch_add(1)) (*f)(s);
  }
};

// Threads that wait for jobs, started once and kept: a region query splits each block of cells
// over the shards, a few thousand times a second under load, and starting a thread per shard per
// block cost more than the shard's part of a small block (docs/performance.md, "A region's
// ceiling, and what came down to it"). A helper takes a ticket of a job and claims its shards;
// the caller claims them too once its own is done, and takes back the tickets no helper has
// taken. So nobody waits on a busy helper: when all are busy the caller does the work alone, as
// the serial path would.
class HelperPool {
 public:
  static HelperPool& Get() {
    // Never destroyed: helpers may still be asleep in Take when static destructors run.
    static HelperPool* const pool = new HelperPool(HelperCount());
    return *pool;
  }

  void Run(size_t shards, const std::function<void(size_t)>& f) ABSL_LOCKS_EXCLUDED(mutex_) {
    Job job{&f, shards};
    const size_t tickets = std::min(shards - 1, helpers_);
    {
      base::MutexLock lock(&mutex_);
      for (size_t i = 0; i < tickets; ++i) queue_.push_back(&job);
    }
    if (tickets == 1) {
      work_.Signal();
    } else {
      work_.SignalAll();
    }
    f(0);
    job.RunClaims();
    base::MutexLock lock(&mutex_);
    // Tickets no helper took are the caller's to drop; the job's memory is the caller's stack, so
    // it returns only when no helper is inside.
    queue_.erase(std::remove(queue_.begin(), queue_.end(), &job), queue_.end());
    while (job.holders > 0) left_.Wait(&mutex_);
  }

 private:
  static size_t HelperCount() {
    // Enough for every shard of a map of eight at once; idle helpers cost a sleeping thread each.
    return std::max<size_t>(std::thread::hardware_concurrency(), 8) - 1;
  }

  explicit HelperPool(size_t helpers) : helpers_(helpers) {
    for (size_t i = 0; i < helpers; ++i) {
      std::thread([this] {
        for (;;) {
          Job* job = Take();
          job->RunClaims();
          Leave(job);
        }
      }).detach();
    }
  }

  // The next ticket's job, waiting for one; the helper is then inside it.
  Job* Take() ABSL_LOCKS_EXCLUDED(mutex_) {
    base::MutexLock lock(&mutex_);
    while (queue_.empty()) work_.Wait(&mutex_);
    Job* job = queue_.front();
    queue_.pop_front();
    ++job->holders;
    return job;
  }

  // Under the mutex: the caller cannot see holders reach 0, and return, before this is done.
  void Leave(Job* job) ABSL_LOCKS_EXCLUDED(mutex_) {
    base::MutexLock lock(&mutex_);
    if (--job->holders == 0) left_.SignalAll();
  }

  const size_t helpers_;
  base::Mutex mutex_;
  base::CondVar work_;  // a ticket was queued
  base::CondVar left_;  // a helper left a job
  std::deque<Job*> queue_ ABSL_GUARDED_BY(mutex_);  // one ticket per helper a job asks for
};

}  // namespace

void ParallelForShards(size_t shards, const std::function<void(size_t)>& f, bool parallel) {
  if (!parallel || shards <= 1) {
    for (size_t s = 0; s < shards; ++s) f(s);
    return;
  }
  HelperPool::Get().Run(shards, f);
}

}  // namespace fremen::storage
