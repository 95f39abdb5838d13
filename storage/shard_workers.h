// One owner thread per shard: RunOnAll(f) runs f(shard) on every shard's thread at once and waits
// for all of them. The committer uses it to apply a group of batches and to checkpoint, so that a
// shard's tables are only ever written by its own thread and the shards work in parallel.
// Thread-safety: RunOnAll is called by one thread at a time (the committer).
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
  // `name` prefixes the threads' names (visible in top -H and gdb).
  ShardWorkers(uint32_t shards, const std::string& name);
  ~ShardWorkers();
  ShardWorkers(const ShardWorkers&) = delete;
  ShardWorkers& operator=(const ShardWorkers&) = delete;

  void RunOnAll(const std::function<void(uint32_t)>& f) ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  void Loop(uint32_t shard) ABSL_LOCKS_EXCLUDED(mutex_);

  base::Mutex mutex_;
  base::CondVar work_ready_, work_done_;
  const std::function<void(uint32_t)>* task_ ABSL_GUARDED_BY(mutex_) = nullptr;
  uint64_t generation_ ABSL_GUARDED_BY(mutex_) = 0;
  uint32_t pending_ ABSL_GUARDED_BY(mutex_) = 0;
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  std::vector<std::thread> threads_;
};

}  // namespace fremen::storage
