#include "server/services/region_plan.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <vector>

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

storage::MapInfo Grid(uint32_t nx, uint32_t ny, uint32_t nz) {
  storage::MapInfo map;
  map.name = "lab";
  map.grid.size = {nx, ny, nz};
  return map;
}

v1::CellIndex Cell(uint32_t x, uint32_t y, uint32_t z) {
  v1::CellIndex c;
  c.set_x(x);
  c.set_y(y);
  c.set_z(z);
  return c;
}

TEST(RegionPlanTest, BoxChecks) {
  const storage::MapInfo grid = Grid(40, 30, 1);
  auto box = RegionBoxOf(grid, Cell(1, 2, 0), Cell(40, 30, 0));  // z unset on a 2-D grid
  ASSERT_TRUE(box.ok()) << box.status();
  EXPECT_EQ(box->hi[2], 1u);
  EXPECT_EQ(box->cell_count(), 39u * 28u);

  absl::Status s = RegionBoxOf(grid, Cell(0, 0, 0), Cell(41, 30, 1)).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(s.message(), HasSubstr("hi.x must be ≤ 40"));
  s = RegionBoxOf(grid, Cell(0, 5, 0), Cell(40, 5, 1)).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(s.message(), HasSubstr("lo.y must be < hi.y"));
  EXPECT_EQ(RegionBoxOf(Grid(8, 8, 4), Cell(0, 0, 0), Cell(8, 8, 0)).status().code(), absl::StatusCode::kOutOfRange);

  storage::MapInfo generic;
  generic.kind = storage::MapKind::kGeneric;
  EXPECT_EQ(RegionBoxOf(generic, Cell(0, 0, 0), Cell(1, 1, 1)).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST(RegionPlanTest, OutputsAndChunkSizes) {
  EXPECT_EQ(*RegionOutputOf(0), v1::REGION_OUTPUT_FLOAT);
  EXPECT_EQ(*RegionOutputOf(v1::REGION_OUTPUT_STATES), v1::REGION_OUTPUT_STATES);
  const absl::Status s = RegionOutputOf(99).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("output 99"));

  EXPECT_EQ(ChunkCells(0, v1::REGION_OUTPUT_FLOAT), kMaxChunkBytes / 4);
  EXPECT_EQ(ChunkCells(0, v1::REGION_OUTPUT_UINT8), kMaxChunkBytes);
  EXPECT_EQ(ChunkCells(1u << 30, v1::REGION_OUTPUT_ENTROPY), kMaxChunkBytes / 4);
  EXPECT_EQ(ChunkCells(100, v1::REGION_OUTPUT_STATES), 100u);
}

// The cells of a box in its order (x fastest), as (x, y, z).
std::vector<std::array<uint32_t, 3>> CellsOf(const storage::CellBox& box) {
  std::vector<std::array<uint32_t, 3>> cells;
  for (uint32_t z = box.lo[2]; z < box.hi[2]; ++z)
    for (uint32_t y = box.lo[1]; y < box.hi[1]; ++y)
      for (uint32_t x = box.lo[0]; x < box.hi[0]; ++x) cells.push_back({x, y, z});
  return cells;
}

// Whatever the chunk size, the chunks are the box's cells in order, each at its offset, none larger
// than asked.
// A series' base chunk: whole bytes of mask, and mask plus values within kMaxChunkBytes.
TEST(RegionPlanTest, BaseChunksFitAMessage) {
  for (const v1::RegionOutput output : {v1::REGION_OUTPUT_FLOAT, v1::REGION_OUTPUT_UINT8}) {
    const uint64_t most = BaseChunkCells(ChunkCells(0, output), output);
    EXPECT_EQ(most % 8, 0u);
    EXPECT_LE(most / 8 + most * BytesPerCell(output), kMaxChunkBytes);
    EXPECT_GT((most + 8) / 8 + (most + 8) * BytesPerCell(output), kMaxChunkBytes);  // the most that fits
  }
  EXPECT_EQ(BaseChunkCells(300, v1::REGION_OUTPUT_FLOAT), 296u);
  EXPECT_EQ(BaseChunkCells(1, v1::REGION_OUTPUT_UINT8), 8u);  // never less than a byte of mask
}

TEST(RegionPlanTest, ChunksTileTheBoxInOrder) {
  const std::vector<storage::CellBox> boxes = {
      {{0, 0, 0}, {1, 1, 1}}, {{3, 2, 1}, {10, 7, 5}}, {{5, 0, 0}, {6, 9, 3}}, {{0, 4, 2}, {13, 5, 3}}};
  for (const storage::CellBox& box : boxes) {
    const uint64_t nx = box.hi[0] - box.lo[0], ny = box.hi[1] - box.lo[1];
    for (uint64_t max : {uint64_t{1}, uint64_t{2}, nx - 1 + (nx == 1), nx, nx + 1, nx * ny, nx * ny + 1,
                         2 * nx * ny + 1, uint64_t{1} << 20}) {
      const RegionPlan plan(box, max);
      const std::vector<std::array<uint32_t, 3>> want = CellsOf(box);
      std::vector<std::array<uint32_t, 3>> got;
      for (uint64_t i = 0; i < plan.chunk_count(); ++i) {
        const RegionPlan::Chunk chunk = plan.chunk(i);
        EXPECT_EQ(chunk.offset, got.size()) << "chunk " << i << " of max " << max;
        EXPECT_LE(chunk.box.cell_count(), max);
        EXPECT_GT(chunk.box.cell_count(), 0u);
        for (const auto& cell : CellsOf(chunk.box)) got.push_back(cell);
      }
      EXPECT_EQ(got, want) << "max " << max;
      EXPECT_EQ(plan.box_cells(), want.size());
    }
  }
}

TEST(RegionPlanTest, EncodesEachOutput) {
  const std::vector<float> p = {0.0f, 0.2f, 0.5f, 0.6f, 1.0f};
  v1::PredictRegionResponse out;
  EncodeRegionValues(v1::REGION_OUTPUT_FLOAT, 0, p, out);
  EXPECT_THAT(out.float_values(), ElementsAre(0.0f, 0.2f, 0.5f, 0.6f, 1.0f));
  EXPECT_TRUE(out.bytes_values().empty());

  EncodeRegionValues(v1::REGION_OUTPUT_UINT8, 0, p, out);
  EXPECT_TRUE(out.float_values().empty());
  EXPECT_THAT(std::vector<uint8_t>(out.bytes_values().begin(), out.bytes_values().end()),
              ElementsAre(0, 51, 128, 153, 255));

  EncodeRegionValues(v1::REGION_OUTPUT_STATES, 0.6f, p, out);
  EXPECT_THAT(std::vector<uint8_t>(out.bytes_values().begin(), out.bytes_values().end()),
              ElementsAre(0, 0, 0, 1, 1));

  EncodeRegionValues(v1::REGION_OUTPUT_ENTROPY, 0, p, out);
  ASSERT_EQ(out.float_values_size(), 5);
  EXPECT_FLOAT_EQ(out.float_values(0), 0.0f);
  EXPECT_NEAR(out.float_values(1), 0.7219f, 1e-4);
  EXPECT_FLOAT_EQ(out.float_values(2), 1.0f);
  EXPECT_FLOAT_EQ(out.float_values(4), 0.0f);
}

}  // namespace
}  // namespace fremen::server
