#include "storage/shard_workers.h"

#include <pthread.h>

namespace fremen::storage {

ShardWorkers::ShardWorkers(uint32_t shards, const std::string& name) : shards_(shards) {
  for (uint32_t i = 1; i < shards; ++i) {
    threads_.emplace_back([this, i] { Loop(i); });
    // Thread names are at most 15 characters.
    pthread_setname_np(threads_.back().native_handle(), (name + std::to_string(i)).substr(0, 15).c_str());
  }
}

ShardWorkers::~ShardWorkers() {
  {
    base::MutexLock lock(&mutex_);
    stopping_ = true;
  }
  work_ready_.SignalAll();
  for (std::thread& t : threads_) t.join();
}

void ShardWorkers::RunOnAll(const std::function<void(uint32_t)>& f, bool parallel) {
  if (!parallel || threads_.empty()) {
    for (uint32_t s = 0; s < shards_; ++s) f(s);
    return;
  }
  {
    base::MutexLock lock(&mutex_);
    task_ = &f;
    pending_ = static_cast<uint32_t>(threads_.size());
    ++generation_;
  }
  work_ready_.SignalAll();
  f(0);
  base::MutexLock lock(&mutex_);
  while (pending_ != 0) work_done_.Wait(&mutex_);
  task_ = nullptr;
}

void ShardWorkers::Loop(uint32_t shard) {
  uint64_t seen = 0;
  for (;;) {
    const std::function<void(uint32_t)>* task;
    {
      base::MutexLock lock(&mutex_);
      while (!stopping_ && generation_ == seen) work_ready_.Wait(&mutex_);
      if (stopping_) return;
      seen = generation_;
      task = task_;
    }
    (*task)(shard);
    {
      base::MutexLock lock(&mutex_);
      if (--pending_ == 0) work_done_.Signal();
    }
  }
}

}  // namespace fremen::storage
