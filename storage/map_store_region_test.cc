// MapStore::PredictBox over boxes that hold whole bricks and parts of bricks, as floats and as
// bytes: every cell must be what a point prediction gives (a byte, its quantisation), for a flat
// and a cubic grid, with never-changed cells at 0 and at 1, unobserved cells, and dynamic ones with
// and without a published model — after the cells have changed kind between two regions, after a
// publication that changes the models (the shards' copy of them brick by brick,
// storage/brick_models.h, is then out of date), at a fixed order and with persistence, and after a
// reopening (the bricks' images, storage/brick_region.h, follow every handle).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "storage/map_store.h"
#include "storage/model/kernels/region_predict.h"
#include "storage/testing/open_map_store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::GridMap;
using testing::OpenOrDie;
using fremen::testing::TempDir;

// Scan i: about 3/4 of the cells with x < observed_x (the rest stay unobserved); cells with
// x % 7 == 0 follow a daily square wave, the others keep one value for ever, 1 where
// (x + 2y + z) % 3 == 0, else 0.
// With `inverted`, the wave is high at night instead.
ObservationBatch Scan(const MapInfo& map, uint64_t i, uint32_t observed_x, bool inverted = false) {
  ObservationBatch b;
  b.writer_id = 1;
  b.sequence = i + 1;
  b.time = 1.7e9 + 3600.0 * static_cast<double>(i);
  const bool day = (std::fmod(b.time, 86400.0) < 43200.0) != inverted;
  const std::array<uint32_t, 3> size = map.grid.size;
  for (uint32_t z = 0; z < size[2]; ++z) {
    for (uint32_t y = 0; y < size[1]; ++y) {
      for (uint32_t x = 0; x < std::min(size[0], observed_x); ++x) {
        if ((x * 7 + y * 13 + z * 3) % 4 != 0) b.keys.push_back(map.grid.keys().Key(x, y, z));  // else never observed
      }
    }
  }
  std::sort(b.keys.begin(), b.keys.end());
  for (const uint64_t key : b.keys) {
    const auto [x, y, z] = map.grid.keys().Cell(key);
    b.values.push_back((x % 7 == 0 ? day : (x + 2 * y + z) % 3 == 0) ? 1.0f : 0.0f);
  }
  return b;
}

// Each box at time t, as floats and as bytes, against the point predictions of its cells.
void ExpectBoxesEqualPoints(const MapStore& store, const MapInfo& map, const std::vector<CellBox>& boxes, double t,
                            const PredictOptions& options = {}) {
  for (const CellBox& box : boxes) {
    std::vector<float> region(box.cell_count(), 7.0f);  // every cell must be written
    ASSERT_TRUE(store.PredictBox(box, t, options, region).ok());
    ASSERT_EQ(region.size(), box.cell_count());
    // The same box as bytes (the UINT8 region), quantised by the shards as they write.
    std::vector<uint8_t> bytes(box.cell_count(), 77);
    ASSERT_TRUE(store.PredictBox(box, t, options, std::span<uint8_t>(bytes)).ok());
    size_t i = 0;
    size_t kinds[4] = {};  // unobserved, never changed at 0, at 1, dynamic
    for (uint32_t z = box.lo[2]; z < box.hi[2]; ++z) {
      for (uint32_t y = box.lo[1]; y < box.hi[1]; ++y) {
        for (uint32_t x = box.lo[0]; x < box.hi[0]; ++x, ++i) {
          const uint64_t key = map.grid.keys().Key(x, y, z);
          const double times[] = {t};
          ASSERT_EQ(region[i], store.Predict({&key, 1}, times, options)[0]) << x << "," << y << "," << z;
          ASSERT_EQ(bytes[i], model::QuantizeProbability(region[i])) << x << "," << y << "," << z;
          const auto snapshot = store.Snapshot(key);
          ++kinds[!snapshot ? 0 : !snapshot->is_static ? 3 : snapshot->static_state.value() == 1.0f ? 2 : 1];
        }
      }
    }
    for (size_t kind = 0; kind < 4; ++kind) EXPECT_GT(kinds[kind], 0u) << "kind " << kind;
  }
}

// `observed_x`: cells from there on are never observed, so that a box may hold bricks no shard has.
void ExpectRegionsEqualPoints(const MapInfo& map, const std::vector<CellBox>& boxes,
                              uint32_t observed_x = UINT32_MAX) {
  TempDir dir;
  auto store = OpenOrDie(map, dir.path());
  // A first few scans, then the rest, which observe more cells and change more of them.
  const double t = 1.7e9 + 3600.0 * 90;
  const uint32_t first_observed_x = std::min(observed_x, map.grid.size[0]) / 2;
  for (uint64_t i = 0; i < 6; ++i) ASSERT_TRUE(store->Write(Scan(map, i, first_observed_x)).ok());
  for (uint64_t i = 6; i < 72; ++i) ASSERT_TRUE(store->Write(Scan(map, i, observed_x)).ok());
  ASSERT_TRUE(store->PublishModels().ok());
  // The first region makes the shards' copy of their models brick by brick, which the memory
  // figure counts.
  const uint64_t memory_before = store->Stats().totals.memory_bytes;
  ExpectBoxesEqualPoints(*store, map, boxes, t);
  EXPECT_GT(store->Stats().totals.memory_bytes, memory_before);
  // Then dynamic states without a published model: cells that change only after the publication.
  ObservationBatch late;
  late.writer_id = 2;
  late.sequence = 1;
  late.time = 1.7e9 + 3600.0 * 80;
  for (uint32_t x = 1; x < map.grid.size[0]; x += 5) {
    const uint64_t key = map.grid.keys().Key(x, 1, 0);
    const auto snapshot = store->Snapshot(key);
    if (!snapshot || !snapshot->is_static) continue;
    late.keys.push_back(key);
    late.values.push_back(1.0f - snapshot->static_state.value());
  }
  ASSERT_FALSE(late.keys.empty());
  ASSERT_TRUE(store->Write(std::move(late)).ok());
  ExpectBoxesEqualPoints(*store, map, boxes, t);
  // The wave turned round, and published: every published model changes.
  for (uint64_t i = 81; i < 153; ++i) ASSERT_TRUE(store->Write(Scan(map, i, observed_x, /*inverted=*/true)).ok());
  ASSERT_TRUE(store->PublishModels().ok());
  ExpectBoxesEqualPoints(*store, map, boxes, t);
  ExpectBoxesEqualPoints(*store, map, boxes, t, {.order = 1});
  ExpectBoxesEqualPoints(*store, map, boxes, t, {.persistence = true});
  // The same after a reopening: the shards load their states from the checkpoint and the log.
  store.reset();
  store = OpenOrDie(map, dir.path());
  ASSERT_NE(store, nullptr);
  ExpectBoxesEqualPoints(*store, map, boxes, t);
}

TEST(MapStoreRegionTest, FlatBoxesOfWholeAndPartBricksEqualPointPredictions) {
  // Bricks of 32×16: the first box holds whole bricks and parts, the second parts only along x.
  ExpectRegionsEqualPoints(GridMap("flat", 80, 40, 1, 2),
                           {CellBox{{0, 0, 0}, {80, 40, 1}}, CellBox{{1, 0, 0}, {64, 33, 1}}});
}

TEST(MapStoreRegionTest, CellsOfBricksNoShardHoldsAreUnobserved) {
  // Cells from x = 40 on never observed: the bricks from x = 64 on exist in no shard, the one of
  // x 32..63 is partly observed. Boxes over all of it, and from inside it.
  ExpectRegionsEqualPoints(GridMap("partly", 130, 40, 1, 2),
                           {CellBox{{0, 0, 0}, {130, 40, 1}}, CellBox{{35, 5, 0}, {129, 37, 1}}}, 40);
}

TEST(MapStoreRegionTest, CubicBoxesOfWholeAndPartBricksEqualPointPredictions) {
  // Bricks of 8×8×8.
  ExpectRegionsEqualPoints(GridMap("cubic", 24, 20, 17, 2),
                           {CellBox{{0, 0, 0}, {24, 20, 17}}, CellBox{{3, 8, 0}, {24, 16, 16}}});
}

}  // namespace
}  // namespace fremen::storage
