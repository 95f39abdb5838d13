#include "storage/parallel_shards.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace fremen::storage {
namespace {

TEST(ParallelForShardsTest, RunsEveryShardExactlyOnce) {
  for (bool parallel : {false, true}) {
    for (size_t shards : {0, 1, 2, 7}) {
      std::vector<std::atomic<int>> runs(shards);
      ParallelForShards(shards, [&](size_t s) { ++runs[s]; }, parallel);
      for (size_t s = 0; s < shards; ++s) EXPECT_EQ(runs[s], 1) << shards << " shards, shard " << s;
    }
  }
}

TEST(ParallelForShardsTest, InParallelEveryShardRunsAtOnceAndSerialOnTheCaller) {
  // Each shard waits until all have started (or gives up after a minute, so that running them one
  // after another fails rather than hangs): every one sees all started only if they run at once.
  constexpr size_t kShards = 4;
  std::atomic<size_t> started = 0, saw_all = 0;
  ParallelForShards(kShards, [&](size_t) {
    ++started;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(1);
    while (started < kShards && std::chrono::steady_clock::now() < give_up) std::this_thread::yield();
    if (started == kShards) ++saw_all;
  });
  EXPECT_EQ(saw_all, kShards);
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<std::thread::id> ran_on(kShards);
  ParallelForShards(kShards, [&](size_t s) { ran_on[s] = std::this_thread::get_id(); }, /*parallel=*/false);
  for (const std::thread::id& id : ran_on) EXPECT_EQ(id, caller);
}

}  // namespace
}  // namespace fremen::storage
