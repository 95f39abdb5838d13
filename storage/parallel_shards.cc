#include "storage/parallel_shards.h"

#include <thread>
#include <vector>

namespace fremen::storage {

void ParallelForShards(size_t shards, const std::function<void(size_t)>& f, bool parallel) {
  if (!parallel || shards <= 1) {
    for (size_t s = 0; s < shards; ++s) f(s);
    return;
  }
  std::vector<std::thread> threads;
  threads.reserve(shards - 1);
  for (size_t s = 1; s < shards; ++s) threads.emplace_back(f, s);
  f(0);
  for (std::thread& t : threads) t.join();
}

}  // namespace fremen::storage
