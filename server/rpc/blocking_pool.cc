#include "server/rpc/blocking_pool.h"

#include <pthread.h>

namespace fremen::server {

BlockingPool::BlockingPool(std::string name, size_t threads, size_t max_queued) : max_queued_(max_queued) {
  for (size_t i = 0; i < threads; ++i) {
    threads_.emplace_back([this] { Run(); });
    const std::string thread_name = (name.substr(0, 10) + "-" + std::to_string(i)).substr(0, 15);
    pthread_setname_np(threads_.back().native_handle(), thread_name.c_str());
  }
}

bool BlockingPool::Post(std::function<void()> work) {
  {
    base::MutexLock lock(&mutex_);
    if (stopping_ || queue_.size() >= max_queued_) return false;
    queue_.push_back(std::move(work));
  }
  ready_.Signal();
  return true;
}

void BlockingPool::Stop() {
  {
    base::MutexLock lock(&mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
  }
  ready_.SignalAll();
  for (std::thread& thread : threads_) thread.join();
  threads_.clear();
}

void BlockingPool::Run() {
  for (;;) {
    std::function<void()> work;
    {
      base::MutexLock lock(&mutex_);
      while (!stopping_ && queue_.empty()) ready_.Wait(&mutex_);
      if (queue_.empty()) return;  // stopping, and everything queued has run
      work = std::move(queue_.front());
      queue_.pop_front();
    }
    work();
  }
}

}  // namespace fremen::server
