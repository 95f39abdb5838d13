#include "storage/shard_workers.h"

#include <pthread.h>

namespace fremen::storage {

ShardWorkers::ShardWorkers(uint32_t shards, const std::string& name) {
  for (uint32_t i = 0; i < shards; ++i) {
    threads_.emplace_back([this, i] { Loop(i); });
    // Thread names are at most 15 characters.
    pthread_setname_np(threads_.back().native_handle(), (name + std::to_string(i)).substr(0, 15).c_str());
  }
}

ShardWorkers::~ShardWorkers() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void ShardWorkers::RunOnAll(const std::function<void(uint32_t)>& f) {
  std::unique_lock lock(mutex_);
  task_ = &f;
  pending_ = static_cast<uint32_t>(threads_.size());
  ++generation_;
  work_ready_.notify_all();
  work_done_.wait(lock, [&] { return pending_ == 0; });
  task_ = nullptr;
}

void ShardWorkers::Loop(uint32_t shard) {
  uint64_t seen = 0;
  for (;;) {
    const std::function<void(uint32_t)>* task;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      task = task_;
    }
    (*task)(shard);
    {
      std::lock_guard lock(mutex_);
      if (--pending_ == 0) work_done_.notify_one();
    }
  }
}

}  // namespace fremen::storage
