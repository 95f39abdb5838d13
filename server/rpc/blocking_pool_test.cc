#include "server/rpc/blocking_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <future>

namespace fremen::server {
namespace {

TEST(BlockingPoolTest, RunsPostedWork) {
  std::promise<int> result;  // before the pool: outlives its threads
  BlockingPool pool("test", 2, 16);
  ASSERT_TRUE(pool.Post([&] { result.set_value(42); }));
  EXPECT_EQ(result.get_future().get(), 42);
}

TEST(BlockingPoolTest, RefusesWorkBeyondTheQueueBound) {
  std::promise<void> release;  // before the pool: outlives its threads
  std::shared_future<void> released = release.get_future().share();
  std::promise<void> started;
  BlockingPool pool("test", 1, 2);
  ASSERT_TRUE(pool.Post([&] {
    started.set_value();
    released.wait();
  }));
  started.get_future().wait();  // the one thread is busy; the queue is empty
  EXPECT_TRUE(pool.Post([] {}));
  EXPECT_TRUE(pool.Post([] {}));
  EXPECT_FALSE(pool.Post([] {}));
  release.set_value();
}

TEST(BlockingPoolTest, StopRunsQueuedWorkThenRefuses) {
  std::atomic<int> ran = 0;
  BlockingPool pool("test", 1, 100);
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(pool.Post([&] { ++ran; }));
  pool.Stop();
  EXPECT_EQ(ran, 50);
  EXPECT_FALSE(pool.Post([] {}));
  pool.Stop();  // idempotent
}

}  // namespace
}  // namespace fremen::server
