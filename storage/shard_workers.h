// The writer's per-shard work: RunOnAll(f) runs f(shard) for every shard at once and waits for all
// of them. The applier uses it to apply a group of batches, to publish and to checkpoint, so that
// the shards work in parallel while one thread at a time writes a shard's tables (the applier, its
// caller, in order with the workers it hands shards to).
// The caller takes shard 0 itself rather than wait idle: a call wakes shards - 1 threads, not
// shards. Work too small to pay for a wake-up (a group of small scans) runs whole on the caller.
// Thread-safety: RunOnAll is called by one thread at a time (the applier).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "base/mutex.h"

namespace fremen::storage {

class ShardWorkers {
 public:
  // `name` prefixes the threads' names (visible in top -H and gdb): name1, name2, ... for the
  // shards the caller hands over.
  ShardWorkers(uint32_t shards, const std::string& name);
  ~ShardWorkers();
  ShardWorkers(const ShardWorkers&) = delete;
  ShardWorkers& operator=(const ShardWorkers&) = delete;

  // With `parallel` false, f(0), f(1), ... run one after another on the caller's thread.
  void RunOnAll(const std::function<void(uint32_t)>& f, bool parallel = true) ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  void Loop(uint32_t shard) ABSL_LOCKS_EXCLUDED(mutex_);

  const uint32_t shards_;
  base::Mutex mutex_;
  base::CondVar work_ready_, work_done_;
  const std::function<void(uint32_t)>* task_ ABSL_GUARDED_BY(mutex_) = nullptr;
  uint64_t generation_ ABSL_GUARDED_BY(mutex_) = 0;
  uint32_t pending_ ABSL_GUARDED_BY(mutex_) = 0;
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  std::vector<std::thread> threads_;  // shards 1 .. shards - 1
};

}  // namespace fremen::storage
