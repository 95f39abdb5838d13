#include "storage/brick_region.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

namespace fremen::storage {
namespace {

// A brick of random handles (unobserved, never changed at 0 or 1, dynamic) written into a box
// larger than the brick, at an offset inside it, as floats or as bytes: every cell of the brick
// must hold what the cell by cell walk gives (as a byte, its QuantizeProbability), every dynamic
// cell must be reported once with its handle and its place, and no cell outside the brick may be
// touched.
enum class Way { kEachCell, kSixteenAtATime };

template <typename T>
void CheckAgainstCellByCell(const GridKeys& keys, Way way, uint64_t seed) {
  const std::array<uint32_t, 3> bs = keys.brick_size();
  const uint64_t nx = bs[0] + 5, ny = bs[1] + 3, nz = bs[2] + 2;
  const std::array<uint64_t, 3> at = {3, 1, bs[2] > 1 ? 1u : 0u};  // the brick's first cell in the box
  std::mt19937_64 rng(seed);
  std::array<uint32_t, 512> handles;
  for (uint32_t& h : handles) {
    switch (rng() % 4) {
      case 0: h = BrickRegion::kNoHandle; break;
      case 1: h = BrickRegion::kNeverChanged | static_cast<uint32_t>(rng() % 2); break;
      case 2: h = BrickRegion::kNeverChanged; break;
      default: h = static_cast<uint32_t>(rng() % 1000000); break;  // a dynamic index
    }
  }
  const T kUntouched = static_cast<T>(77);  // neither 0, 0.5, 1 nor their bytes 0, 128, 255
  std::vector<T> box(nx * ny * nz, kUntouched);
  const BrickRegion region(keys, nx, ny);
  T* origin = box.data() + (at[2] * ny + at[1]) * nx + at[0];
  std::map<const T*, uint32_t> reported;
  const auto report = [&](uint32_t handle, T* cell) {
    EXPECT_TRUE(reported.emplace(cell, handle).second) << "a dynamic cell reported twice";
  };
  if (way == Way::kEachCell) {
    region.WriteEachCell(handles.data(), origin, report);
  } else {
#if defined(__SSE2__)
    region.WriteSixteenAtATime(handles.data(), origin, report);
#endif
  }
  size_t dynamic = 0;
  for (uint64_t z = 0; z < nz; ++z) {
    for (uint64_t y = 0; y < ny; ++y) {
      for (uint64_t x = 0; x < nx; ++x) {
        const T* cell = &box[(z * ny + y) * nx + x];
        const bool inside = x >= at[0] && x < at[0] + bs[0] && y >= at[1] && y < at[1] + bs[1] &&
                            z >= at[2] && z < at[2] + bs[2];
        if (!inside) {
          ASSERT_EQ(*cell, kUntouched) << "outside the brick: " << x << "," << y << "," << z;
          continue;
        }
        const uint32_t i = keys.LocalIndex(static_cast<uint32_t>(x - at[0]), static_cast<uint32_t>(y - at[1]),
                                           static_cast<uint32_t>(z - at[2]));
        ASSERT_EQ(cell, origin + region.offset(i));
        const uint32_t h = handles[i];
        if (h == BrickRegion::kNoHandle) {
          ASSERT_EQ(*cell, CellValue<T>(kUnobservedProbability)) << x << "," << y << "," << z;
        } else if (h & BrickRegion::kNeverChanged) {
          ASSERT_EQ(*cell, CellValue<T>(static_cast<float>(h & 1u))) << x << "," << y << "," << z;
        } else {
          ++dynamic;
          const auto it = reported.find(cell);
          ASSERT_NE(it, reported.end()) << "dynamic cell not reported: " << x << "," << y << "," << z;
          EXPECT_EQ(it->second, h);
        }
      }
    }
  }
  EXPECT_GT(dynamic, 0u);
  EXPECT_EQ(reported.size(), dynamic);
}

// Write takes the sixteen-at-a-time way on x86-64 (SSE2) and the cell-by-cell way elsewhere; both
// are checked here wherever they compile.
template <typename T>
void CheckBothWays(const GridKeys& keys) {
  for (uint64_t seed = 1; seed <= 20; ++seed) CheckAgainstCellByCell<T>(keys, Way::kEachCell, seed);
#if defined(__SSE2__)
  for (uint64_t seed = 1; seed <= 20; ++seed) CheckAgainstCellByCell<T>(keys, Way::kSixteenAtATime, seed);
#endif
}

TEST(BrickRegionTest, FlatBrickEqualsTheCellByCellWalk) {
  CheckBothWays<float>(GridKeys::For(1));
  CheckBothWays<uint8_t>(GridKeys::For(1));
}

TEST(BrickRegionTest, CubicBrickEqualsTheCellByCellWalk) {
  CheckBothWays<float>(GridKeys::For(8));
  CheckBothWays<uint8_t>(GridKeys::For(8));
}

// A byte is round(255·p): 0, 128 (an unobserved cell's 0.5) and 255.
TEST(BrickRegionTest, BytesAreTheQuantisedProbabilities) {
  EXPECT_EQ(CellValue<uint8_t>(0.0f), 0);
  EXPECT_EQ(CellValue<uint8_t>(kUnobservedProbability), 128);
  EXPECT_EQ(CellValue<uint8_t>(1.0f), 255);
  EXPECT_EQ(CellValue<float>(0.25f), 0.25f);
}

}  // namespace
}  // namespace fremen::storage
