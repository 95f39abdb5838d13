#include "storage/parallel_shards.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

namespace fremen::storage {

namespace {

// One ParallelForShards call: its shards are claimed one at a time, by the caller and by the
// helpers that took one of its tickets, until none is left.
struct Job {
  const std::function<void(size_t)>* f;
  size_t shards;
  std::atomic<size_t> next{1};  // shard 0 is the caller's
  size_t holders = 0;           // helpers inside the job (guarded by the pool's mutex)

  // Runs the shards left, one claim at a time.
  void RunClaims() {
    for (size_t s = next.fetch_add(1); s < shards; s = next.fetch_add(1)) (*f)(s);
  }
};

// Threads that wait for jobs, started once and kept: a region query splits each block of cells
// over the shards, a few thousand times a second under load, and starting a thread per shard per
// block cost more than the shard's part of a small block (docs/performance.md, "A region, block
// by block"). A helper takes a ticket of a job and claims its shards; the caller claims them too
// once its own is done, and takes back the tickets no helper has taken. So nobody waits on a busy
// helper: when all are busy the caller does the work alone, as the serial path would.
class HelperPool {
 public:
  static HelperPool& Get() {
    // Never destroyed: helpers may still be asleep in Wait when static destructors run.
    static HelperPool* const pool = new HelperPool(HelperCount());
    return *pool;
  }

  void Run(size_t shards, const std::function<void(size_t)>& f) {
    Job job{&f, shards};
    const size_t tickets = std::min(shards - 1, helpers_);
    {
      std::lock_guard lock(mutex_);
      for (size_t i = 0; i < tickets; ++i) queue_.push_back(&job);
    }
    if (tickets == 1) {
      work_.notify_one();
    } else {
      work_.notify_all();
    }
    f(0);
    job.RunClaims();
    std::unique_lock lock(mutex_);
    // Tickets no helper took are the caller's to drop; the job's memory is the caller's stack, so
    // it returns only when no helper is inside.
    queue_.erase(std::remove(queue_.begin(), queue_.end(), &job), queue_.end());
    left_.wait(lock, [&] { return job.holders == 0; });
  }

 private:
  static size_t HelperCount() {
    // Enough for every shard of a map of eight at once; idle helpers cost a sleeping thread each.
    return std::max<size_t>(std::thread::hardware_concurrency(), 8) - 1;
  }

  explicit HelperPool(size_t helpers) : helpers_(helpers) {
    for (size_t i = 0; i < helpers; ++i) std::thread([this] { Serve(); }).detach();
  }

  void Serve() {
    std::unique_lock lock(mutex_);
    for (;;) {
      work_.wait(lock, [&] { return !queue_.empty(); });
      Job* job = queue_.front();
      queue_.pop_front();
      ++job->holders;
      lock.unlock();
      job->RunClaims();
      lock.lock();
      // Under the mutex: the caller cannot see holders reach 0, and return, before this is done.
      if (--job->holders == 0) left_.notify_all();
    }
  }

  const size_t helpers_;
  std::mutex mutex_;
  std::condition_variable work_;  // a ticket was queued
  std::condition_variable left_;  // a helper left a job
  std::deque<Job*> queue_;        // one ticket per helper a job asks for
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
