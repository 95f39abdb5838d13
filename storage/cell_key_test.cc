#include "storage/cell_key.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace fremen::storage {
namespace {

TEST(CellKeyTest, MortonRoundTripsAndInterleaves) {
  EXPECT_EQ(MortonKey(1, 0, 0), 1u);
  EXPECT_EQ(MortonKey(0, 1, 0), 2u);
  EXPECT_EQ(MortonKey(0, 0, 1), 4u);
  EXPECT_EQ(MortonKey(3, 3, 3), 63u);
  std::mt19937 rng(1);
  std::uniform_int_distribution<uint32_t> any(0, kMaxGridIndex);
  for (int i = 0; i < 10000; ++i) {
    const uint32_t x = any(rng), y = any(rng), z = any(rng);
    const auto cell = MortonCell(MortonKey(x, y, z));
    ASSERT_EQ(cell[0], x);
    ASSERT_EQ(cell[1], y);
    ASSERT_EQ(cell[2], z);
  }
}

TEST(CellKeyTest, AnAlignedBlockIsOneBrick) {
  std::set<uint64_t> bricks;
  for (uint32_t x = 8; x < 16; ++x)
    for (uint32_t y = 16; y < 24; ++y)
      for (uint32_t z = 0; z < 8; ++z) bricks.insert(BrickOf(MortonKey(x, y, z)));
  EXPECT_EQ(bricks.size(), 1u);
}

TEST(CellKeyTest, ShardsAreBalancedAndBrickAligned) {
  std::vector<int> per_shard(4, 0);
  for (uint32_t x = 0; x < 256; ++x)
    for (uint32_t y = 0; y < 256; ++y) per_shard[ShardOf(MortonKey(x, y, 0), 4)]++;
  for (int count : per_shard) EXPECT_NEAR(count, 65536 / 4, 65536 / 16);
  EXPECT_EQ(ShardOf(MortonKey(8, 8, 8), 4), ShardOf(MortonKey(15, 15, 15), 4));
}

TEST(CellKeyTest, KeyBytesSortLikeKeys) {
  const auto a = KeyBytes(0x0102030405060708ull);
  EXPECT_EQ(KeyFromBytes(a.data()), 0x0102030405060708ull);
  EXPECT_LT(KeyBytes(255), KeyBytes(256));
}

}  // namespace
}  // namespace fremen::storage

namespace fremen::storage {
namespace {

TEST(GridKeysTest, FlatGridsUseDenseTwoDimensionalKeys) {
  const GridKeys flat = GridKeys::For(1), deep = GridKeys::For(4);
  EXPECT_TRUE(flat.flat());
  EXPECT_FALSE(deep.flat());
  std::mt19937 rng(2);
  std::uniform_int_distribution<uint32_t> any(0, kMaxGridIndex);
  for (int i = 0; i < 10000; ++i) {
    const uint32_t x = any(rng), y = any(rng), z = any(rng);
    ASSERT_EQ(flat.Cell(flat.Key(x, y, 0)), (std::array<uint32_t, 3>{x, y, 0}));
    ASSERT_EQ(deep.Cell(deep.Key(x, y, z)), (std::array<uint32_t, 3>{x, y, z}));
    ASSERT_TRUE(flat.IsCellKey(flat.Key(x, y, 0)));
  }
  // A 32×16 block of a 2-D grid is one brick of 512 consecutive keys.
  std::set<uint64_t> bricks, keys;
  for (uint32_t x = 64; x < 96; ++x) {
    for (uint32_t y = 16; y < 32; ++y) {
      bricks.insert(BrickOf(flat.Key(x, y, 0)));
      keys.insert(flat.Key(x, y, 0));
      EXPECT_EQ(flat.LocalIndex(x, y, 0), flat.Key(x, y, 0) & 511);
    }
  }
  EXPECT_EQ(bricks.size(), 1u);
  EXPECT_EQ(*keys.rbegin() - *keys.begin(), 511u);
  EXPECT_EQ(deep.LocalIndex(9, 10, 11), deep.Key(9, 10, 11) & 511);
  EXPECT_FALSE(flat.IsCellKey(uint64_t{1} << 50));
}

}  // namespace
}  // namespace fremen::storage

#include "storage/state_names.h"

namespace fremen::storage {
namespace {

TEST(StateNamesTest, NamesMapToStableDistinctIds) {
  EXPECT_EQ(StateIdOfName(""), 0xcbf29ce484222325ull);   // FNV-1a's offset basis
  EXPECT_EQ(StateIdOfName("a"), 0xaf63dc4c8601ec8cull);  // the published FNV-1a 64 test vector
  std::set<uint64_t> ids;
  for (int i = 0; i < 100000; ++i) ids.insert(StateIdOfName("door" + std::to_string(i)));
  EXPECT_EQ(ids.size(), 100000u);
}

}  // namespace
}  // namespace fremen::storage
