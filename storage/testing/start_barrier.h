// A test's proof that tasks run at once: each task calls Arrive, which waits until all `count` have
// arrived (or gives up after a minute, so that tasks run one after another fail the test rather
// than hang it) and says whether it saw them all.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <thread>

namespace fremen::storage::testing {

class StartBarrier {
 public:
  explicit StartBarrier(size_t count) : count_(count) {}

  bool Arrive() {
    ++arrived_;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(1);
    while (arrived_ < count_ && std::chrono::steady_clock::now() < give_up) std::this_thread::yield();
    return arrived_ == count_;
  }

 private:
  const size_t count_;
  std::atomic<size_t> arrived_ = 0;
};

}  // namespace fremen::storage::testing
