#include "storage/parallel_shards.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
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

// The helpers are shared by every caller: when all are busy, a call does its shards itself rather
// than wait for one. Here a first call holds every helper (and its caller) until a second call,
// made meanwhile on another thread, has finished all its shards.
TEST(ParallelForShardsTest, ACallWhoseHelpersAreAllBusyRunsItsShardsItself) {
  std::promise<void> second_done;
  std::shared_future<void> released = second_done.get_future().share();
  constexpr size_t kBusyShards = 64;  // more than there are helpers
  std::atomic<size_t> busy_started = 0;
  std::thread holder([&] {
    ParallelForShards(kBusyShards, [&](size_t) {
      ++busy_started;
      released.wait_for(std::chrono::minutes(1));  // a bound, so that a failure ends the test
    });
  });
  while (busy_started == 0) std::this_thread::yield();
  std::vector<std::atomic<int>> runs(4);
  auto second = std::async(std::launch::async, [&] { ParallelForShards(runs.size(), [&](size_t s) { ++runs[s]; }); });
  const bool finished = second.wait_for(std::chrono::seconds(50)) == std::future_status::ready;
  second_done.set_value();
  holder.join();
  second.wait();
  EXPECT_TRUE(finished) << "the second call waited for the busy helpers";
  for (size_t s = 0; s < runs.size(); ++s) EXPECT_EQ(runs[s], 1) << "shard " << s;
  EXPECT_EQ(busy_started, kBusyShards);
}

// A shard's work may itself split over the shards (the helpers never wait on anything).
TEST(ParallelForShardsTest, NestedCallsFinish) {
  std::atomic<int> inner_runs = 0;
  ParallelForShards(4, [&](size_t) { ParallelForShards(4, [&](size_t) { ++inner_runs; }); });
  EXPECT_EQ(inner_runs, 16);
}

}  // namespace
}  // namespace fremen::storage
