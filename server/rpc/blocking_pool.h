// Threads for RPC work that waits on disk — creating and deleting maps, backups — so that gRPC's
// callback threads never block (a reaction never waits on a lock or on disk). The queue is bounded:
// Post refuses work when it is full, and the caller answers RESOURCE_EXHAUSTED rather than letting
// work pile up without bound.
// Thread-safety: Post may be called from any thread. Stop() (also run by the destructor) is for
// the owner's thread: it runs the queued work, then joins the threads; Post after Stop refuses.
#pragma once

#include <cstddef>
#include <deque>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "base/mutex.h"

namespace fremen::server {

class BlockingPool {
 public:
  // `name` prefixes the threads' names (at most 10 characters shown by ps/top).
  BlockingPool(std::string name, size_t threads, size_t max_queued);
  ~BlockingPool() { Stop(); }
  BlockingPool(const BlockingPool&) = delete;
  BlockingPool& operator=(const BlockingPool&) = delete;

  // Queues `work`; false when the queue is full or the pool is stopping.
  [[nodiscard]] bool Post(std::function<void()> work) ABSL_LOCKS_EXCLUDED(mutex_);
  void Stop() ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  void Run() ABSL_LOCKS_EXCLUDED(mutex_);

  const size_t max_queued_;
  base::Mutex mutex_;
  base::CondVar ready_;
  std::deque<std::function<void()>> queue_ ABSL_GUARDED_BY(mutex_);
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  std::vector<std::thread> threads_;  // the constructor's and Stop's (the owner's thread)
};

}  // namespace fremen::server
