#include "storage/brick_region.h"

#include <gtest/gtest.h>

#include <array>
#include <map>
#include <random>
#include <set>
#include <vector>

namespace fremen::storage {
namespace {

// Every cell of a brick has one row-major place, and X, Y, Z give back its axes.
void CheckLayout(const GridKeys& keys) {
  const BrickLayout layout(keys);
  const std::array<uint32_t, 3> bs = keys.brick_size();
  ASSERT_EQ(layout.size(), bs);
  std::set<uint32_t> seen;
  for (uint32_t z = 0; z < bs[2]; ++z) {
    for (uint32_t y = 0; y < bs[1]; ++y) {
      for (uint32_t x = 0; x < bs[0]; ++x) {
        const uint32_t i = layout.RowMajor(keys.LocalIndex(x, y, z));
        EXPECT_EQ(i, (z * bs[1] + y) * bs[0] + x);
        EXPECT_EQ(layout.X(i), x);
        EXPECT_EQ(layout.Y(i), y);
        EXPECT_EQ(layout.Z(i), z);
        seen.insert(i);
      }
    }
  }
  EXPECT_EQ(seen.size(), 512u);
}

TEST(BrickLayoutTest, EachCellHasOneRowMajorPlace) {
  CheckLayout(GridKeys::For(1));
  CheckLayout(GridKeys::For(8));
}

// A brick whose cells go through the handles a shard gives them — unobserved, then never changed
// at 0 or 1, then dynamic, each cell stopping at a random step — and rows of it copied whole and
// in parts, as floats and as bytes: each never-changed or unobserved cell must be its p (as a
// byte, its quantisation), no cell outside the copied part touched, and the dynamic cells listed
// once each with their handle.
template <typename T>
void CheckImage(uint64_t seed) {
  std::mt19937_64 rng(seed);
  BrickImage image;
  std::array<uint32_t, 512> handles;
  handles.fill(BrickImage::kNoHandle);
  uint32_t next_dynamic = 1000;
  for (int step = 0; step < 3; ++step) {
    for (uint32_t i = 0; i < 512; ++i) {
      const uint32_t h = handles[i];
      if (rng() % 3 == 0 || !(h & BrickImage::kNeverChanged)) continue;  // stays; dynamic stays for good
      // Unobserved → never changed (or straight to dynamic); never changed → dynamic.
      handles[i] = h == BrickImage::kNoHandle && rng() % 4 != 0
                       ? BrickImage::kNeverChanged | static_cast<uint32_t>(rng() % 2)
                       : next_dynamic++;
      image.Set(i, handles[i]);
    }
  }
  std::map<uint32_t, uint32_t> listed;  // cell → handle
  for (const BrickImage::DynamicCell& cell : image.dynamic()) {
    EXPECT_TRUE(listed.emplace(cell.cell, cell.handle).second) << "cell " << cell.cell << " listed twice";
  }
  size_t kinds[4] = {};  // unobserved, at 0, at 1, dynamic
  for (uint32_t i = 0; i < 512; ++i) {
    const uint32_t h = handles[i];
    if (h & BrickImage::kNeverChanged) {
      ++kinds[h == BrickImage::kNoHandle ? 0 : 1 + (h & 1u)];
      EXPECT_EQ(listed.count(i), 0u) << i;
    } else {
      ++kinds[3];
      ASSERT_EQ(listed.count(i), 1u) << "dynamic cell " << i << " not listed";
      EXPECT_EQ(listed[i], h);
    }
  }
  for (size_t kind = 0; kind < 4; ++kind) ASSERT_GT(kinds[kind], 0u) << "kind " << kind;

  const T kUntouched = static_cast<T>(77);  // neither 0, 0.5, 1 nor their bytes 0, 128, 255
  for (uint32_t first = 0; first < 512; first += 37) {
    for (const uint32_t n : {1u, 7u, 16u, 21u, 32u}) {
      if (first + n > 512) continue;
      std::array<T, 34> out;  // a row of up to 32 cells between two that must stay untouched
      out.fill(kUntouched);
      image.CopyRow(first, n, out.data() + 1);
      EXPECT_EQ(out[0], kUntouched);
      EXPECT_EQ(out[n + 1], kUntouched);
      for (uint32_t k = 0; k < n; ++k) {
        const uint32_t h = handles[first + k];
        if (!(h & BrickImage::kNeverChanged)) continue;  // the caller's to write
        const float p = h == BrickImage::kNoHandle ? kUnobservedProbability : static_cast<float>(h & 1u);
        ASSERT_EQ(out[1 + k], CellValue<T>(p)) << "cell " << first + k << " of a row of " << n;
      }
    }
  }
}

TEST(BrickImageTest, RowsHoldTheNeverChangedAndUnobservedCellsAndTheDynamicOnesAreListed) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    CheckImage<float>(seed);
    CheckImage<uint8_t>(seed);
  }
}

// A byte is round(255·p): 0, 128 (an unobserved cell's 0.5) and 255.
TEST(BrickImageTest, BytesAreTheQuantisedProbabilities) {
  EXPECT_EQ(CellValue<uint8_t>(0.0f), 0);
  EXPECT_EQ(CellValue<uint8_t>(kUnobservedProbability), 128);
  EXPECT_EQ(CellValue<uint8_t>(1.0f), 255);
  EXPECT_EQ(CellValue<float>(0.25f), 0.25f);
}

}  // namespace
}  // namespace fremen::storage
