#include "storage/shard_workers.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "storage/testing/start_barrier.h"

namespace fremen::storage {
namespace {

TEST(ShardWorkersTest, EveryCallRunsEveryShardExactlyOnce) {
  for (uint32_t shards : {1u, 2u, 5u}) {
    ShardWorkers workers(shards, "test");
    for (int call = 0; call < 50; ++call) {
      const bool parallel = call % 3 != 0;
      std::vector<std::atomic<int>> runs(shards);
      workers.RunOnAll([&](uint32_t s) { ++runs[s]; }, parallel);
      for (uint32_t s = 0; s < shards; ++s) {
        ASSERT_EQ(runs[s], 1) << shards << " shards, call " << call << ", shard " << s;
      }
    }
  }
}

TEST(ShardWorkersTest, InParallelTheCallerTakesShardZeroAndTheOthersRunAtOnce) {
  constexpr uint32_t kShards = 4;
  ShardWorkers workers(kShards, "test");
  // Every shard sees all started only if they run at once.
  testing::StartBarrier barrier(kShards);
  std::atomic<uint32_t> saw_all = 0;
  std::vector<std::thread::id> ran_on(kShards);
  workers.RunOnAll([&](uint32_t s) {
    ran_on[s] = std::this_thread::get_id();
    saw_all += barrier.Arrive();
  });
  EXPECT_EQ(saw_all, kShards);
  const std::thread::id caller = std::this_thread::get_id();
  EXPECT_EQ(ran_on[0], caller);
  for (uint32_t s = 1; s < kShards; ++s) EXPECT_NE(ran_on[s], caller) << "shard " << s;
}

TEST(ShardWorkersTest, SerialWorkRunsInShardOrderOnTheCaller) {
  ShardWorkers workers(3, "test");
  std::vector<uint32_t> order;
  std::vector<std::thread::id> ran_on;
  workers.RunOnAll(
      [&](uint32_t s) {
        order.push_back(s);
        ran_on.push_back(std::this_thread::get_id());
      },
      /*parallel=*/false);
  EXPECT_EQ(order, (std::vector<uint32_t>{0, 1, 2}));
  for (const std::thread::id& id : ran_on) EXPECT_EQ(id, std::this_thread::get_id());
}

}  // namespace
}  // namespace fremen::storage
