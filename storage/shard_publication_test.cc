// Shard's publication slices (shard_publication.cc): incremental states are published a fixed
// number at a time under the shard's exclusive lock, so that readers wait for one chunk at most.
#include <gtest/gtest.h>

#include "storage/shard.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

TEST(ShardPublicationTest, PublishesIncrementalStatesInChunksOf1024PerLock) {
  fremen::testing::TempDir dir;
  const MapInfo info = testing::GridMap("chunks", 50, 60, 1, 1);  // 3000 cells, one shard
  auto settings = ModelSettingsOf(info);
  ASSERT_TRUE(settings.ok()) << settings.status();
  auto shard = Shard::Open(info, *settings, dir.path() + "/shard-0", LmdbOptions{});
  ASSERT_TRUE(shard.ok()) << shard.status();
  // Two scans of opposite values make every cell dynamic and touched.
  std::vector<uint64_t> keys;
  for (uint32_t y = 0; y < 60; ++y) {
    for (uint32_t x = 0; x < 50; ++x) keys.push_back(info.grid.keys().Key(x, y, 0));
  }
  for (int i = 0; i < 2; ++i) {
    const std::vector<float> values(keys.size(), static_cast<float>(i));
    (*shard)->Apply(ScanContext(settings->periods, 1.7e9 + 600.0 * i), keys, values);
  }
  ASSERT_EQ((*shard)->BeginPublication(), 3000u);
  // A zero budget ends each call after its first chunk.
  EXPECT_FALSE((*shard)->ContinuePublication(std::chrono::nanoseconds(0)));
  EXPECT_EQ((*shard)->publication_done(), 1024u);
  EXPECT_FALSE((*shard)->ContinuePublication(std::chrono::nanoseconds(0)));
  EXPECT_EQ((*shard)->publication_done(), 2048u);
  EXPECT_TRUE((*shard)->ContinuePublication(std::chrono::nanoseconds(0)));
  EXPECT_EQ((*shard)->publication_done(), 3000u);
}

}  // namespace
}  // namespace fremen::storage
