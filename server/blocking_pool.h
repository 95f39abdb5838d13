// Threads for RPC work that waits on disk — creating and deleting maps, backups — so that gRPC's
// callback threads never block (a reaction never waits on a lock or on disk). The queue is bounded:
// Post refuses work when it is full, and the caller answers RESOURCE_EXHAUSTED rather than letting
// work pile up without bound.
// Thread-safety: Post may be called from any thread. Stop() (also run by the destructor) is for
// the owner's thread: it runs the queued work, then joins the threads; Post after Stop refuses.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace fremen::server {

class BlockingPool {
 public:
  // `name` prefixes the threads' names (at most 10 characters shown by ps/top).
  BlockingPool(std::string name, size_t threads, size_t max_queued);
  ~BlockingPool() { Stop(); }
  BlockingPool(const BlockingPool&) = delete;
  BlockingPool& operator=(const BlockingPool&) = delete;

  // Queues `work`; false when the queue is full or the pool is stopping.
  [[nodiscard]] bool Post(std::function<void()> work);
  void Stop();

 private:
  void Run();

  const size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> queue_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace fremen::server
