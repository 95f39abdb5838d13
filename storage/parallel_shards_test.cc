#include "storage/parallel_shards.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "storage/testing/start_barrier.h"

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
  // Every shard sees all started only if they run at once.
  constexpr size_t kShards = 4;
  testing::StartBarrier barrier(kShards);
  std::atomic<size_t> saw_all = 0;
  ParallelForShards(kShards, [&](size_t) { saw_all += barrier.Arrive(); });
  EXPECT_EQ(saw_all, kShards);
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<std::thread::id> ran_on(kShards);
  ParallelForShards(kShards, [&](size_t s) { ran_on[s] = std::this_thread::get_id(); }, /*parallel=*/false);
  for (const std::thread::id& id : ran_on) EXPECT_EQ(id, caller);
}

}  // namespace
}  // namespace fremen::storage
