#include "storage/compact_cells.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "base/compact_scan.h"
#include "storage/batch.h"
#include "storage/cell_key.h"

namespace fremen::storage {
namespace {

GridGeometry Grid(uint32_t x, uint32_t y, uint32_t z) {
  GridGeometry grid;
  grid.size = {x, y, z};
  return grid;
}

// The keys and values of cells by linear index, computed the plain way (divisions per cell).
void Reference(const GridGeometry& grid, const std::vector<uint64_t>& indices, std::vector<uint64_t>& keys) {
  for (uint64_t i : indices) {
    if (i >= grid.cell_count()) {
      keys.push_back(kNotACellKey);
      continue;
    }
    const uint64_t layer = uint64_t{grid.size[0]} * grid.size[1];
    keys.push_back(grid.keys().Key(static_cast<uint32_t>(i % grid.size[0]),
                                   static_cast<uint32_t>(i % layer / grid.size[0]),
                                   static_cast<uint32_t>(i / layer)));
  }
}

absl::Status Expand(const GridGeometry& grid, const CompactCells& cells) {
  UninitializedVector<uint64_t> keys;
  UninitializedVector<float> values;
  return ExpandCompactCells(grid, cells, 1 << 28, keys, values);
}

TEST(CompactCellsTest, RandomScansExpandToTheKeysOfTheirCellsIn2DAnd3D) {
  std::mt19937_64 random(3);
  for (const GridGeometry& grid :
       {Grid(100, 100, 100), Grid(37, 5, 1), Grid(1, 1, 7), Grid(300, 2, 3), Grid(1030, 3, 1), Grid(600, 2, 2)}) {
    for (int round = 0; round < 20; ++round) {
      std::vector<uint64_t> indices;
      std::vector<float> values;
      // Runs of neighbours and jumps, some past the grid's end.
      uint64_t index = random() % 50;
      for (int i = 0; i < 500; ++i) {
        indices.push_back(index);
        values.push_back(static_cast<float>(random() % 2));
        index += random() % 8 == 0 ? 1 + random() % (2 * grid.size[0] * grid.size[1]) : 1;
      }
      CompactCells cells{EncodeIndexGaps(indices), PackOccupiedBits(values), ""};
      UninitializedVector<uint64_t> keys;
      std::vector<uint64_t> want;
      UninitializedVector<float> got_values;
      ASSERT_TRUE(ExpandCompactCells(grid, cells, 1 << 28, keys, got_values).ok());
      Reference(grid, indices, want);
      EXPECT_EQ(keys, want);
      EXPECT_EQ(got_values, values);
    }
  }
}

// A whole-grid sweep (every gap 1, rows ending in the middle of a run of bytes) and a few cells
// past the grid's end: the run fast path leaves each row at its last cell. Rows wider than 256
// and 512 cells cross the run's x lookups' blocks.
TEST(CompactCellsTest, AWholeGridSweepExpandsToEveryCellsKeyInOrder) {
  for (const GridGeometry& grid :
       {Grid(37, 5, 1), Grid(8, 3, 2), Grid(2, 2, 2), Grid(584, 3, 1), Grid(1030, 2, 1), Grid(600, 2, 3)}) {
    std::vector<uint64_t> indices;
    std::vector<float> values;
    for (uint64_t i = 0; i < grid.cell_count() + 3; ++i) {
      indices.push_back(i);
      values.push_back(static_cast<float>(i % 3 == 0));
    }
    CompactCells cells{EncodeIndexGaps(indices), PackOccupiedBits(values), ""};
    UninitializedVector<uint64_t> keys;
    std::vector<uint64_t> want;
    UninitializedVector<float> got_values;
    ASSERT_TRUE(ExpandCompactCells(grid, cells, 1 << 28, keys, got_values).ok());
    Reference(grid, indices, want);
    EXPECT_EQ(keys, want) << grid.size[0] << "x" << grid.size[1] << "x" << grid.size[2];
    EXPECT_EQ(got_values, values);
  }
}

TEST(CompactCellsTest, ProbabilitiesAreBytesOver255AsAPatchs) {
  CompactCells cells{EncodeIndexGaps(std::vector<uint64_t>{0, 1, 5}), "", std::string("\x00\x33\xff", 3)};
  UninitializedVector<uint64_t> keys;
  UninitializedVector<float> values;
  ASSERT_TRUE(ExpandCompactCells(Grid(4, 4, 1), cells, 100, keys, values).ok());
  EXPECT_EQ(values, (std::vector<float>{0.0f, 0.2f, 1.0f}));
  EXPECT_EQ(keys[2], Grid(4, 4, 1).keys().Key(1, 1, 0));
}

TEST(CompactCellsTest, MalformedBytesAreInvalidArgumentNamingTheField) {
  const GridGeometry grid = Grid(10, 10, 1);
  const std::string two = EncodeIndexGaps(std::vector<uint64_t>{1, 2});
  const auto message = [&](const CompactCells& c) {
    absl::Status s = Expand(grid, c);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
    return std::string(s.message());
  };
  EXPECT_EQ(message({"\x01\x80", "\x01", ""}), "compact.indices: the last varint is truncated (its last byte has the continuation bit set)");
  EXPECT_EQ(message({std::string("\x01\x00", 2), "\x01", ""}), "compact.indices: the gap before cell 1 is 0; indices must increase strictly");
  EXPECT_EQ(message({std::string("\x81\x00", 2), "\x01", ""}), "compact.indices: the varint of cell 0 is not in its shortest form");
  EXPECT_EQ(message({std::string(9, '\xff') + "\x02", "\x01", ""}), "compact.indices: the varint of cell 0 exceeds 64 bits");
  EXPECT_EQ(message({two, "", ""}), "compact: one of occupied or probabilities is required for the 2 cells");
  EXPECT_EQ(message({two, "\x01", "ab"}), "compact: set occupied or probabilities, not both");
  EXPECT_EQ(message({two, std::string("\x01\x00", 2), ""}), "compact.occupied has 2 bytes for 2 cells (compact.indices); want one bit per cell, 1 bytes");
  EXPECT_EQ(message({two, "\x04", ""}), "compact.occupied: the bits past the last cell (2) must be 0");
  EXPECT_EQ(message({two, "", "a"}), "compact.probabilities has 1 bytes for 2 cells (compact.indices); want one per cell");
  UninitializedVector<uint64_t> keys;
  UninitializedVector<float> values;
  EXPECT_EQ(ExpandCompactCells(grid, {two, "\x01", ""}, 1, keys, values).message(),
            "compact.indices holds 2 cells; a batch may hold at most 1");
}

TEST(CompactCellsTest, CellsPastTheGridGetNoCellsKeyAndClassifyRejectsThemAsOutside) {
  MapInfo map;
  map.grid.size = {10, 10, 1};
  ObservationBatch batch;
  batch.compact = {EncodeIndexGaps(std::vector<uint64_t>{98, 99, 100, ~uint64_t{0}}),
                   PackOccupiedBits(std::vector<float>{1, 0, 1, 1}), ""};
  ASSERT_TRUE(ExpandCompact(map, batch).ok());
  EXPECT_EQ(batch.keys[1], map.grid.keys().Key(9, 9, 0));
  EXPECT_EQ(batch.keys[2], kNotACellKey);
  EXPECT_EQ(batch.keys[3], kNotACellKey);
  EXPECT_EQ(batch.keys_from_grid.outside, 2u);
  std::vector<uint8_t> accept;
  const BatchAck ack = Classify(map, batch, accept);
  EXPECT_EQ(accept, (std::vector<uint8_t>{1, 1, 0, 0}));
  EXPECT_EQ(ack.rejected, 2u);
  for (const Rejection& r : ack.rejections) EXPECT_EQ(r.reason, RejectReason::kOutsideMap) << r.index;
}

// Classify trusts the expansion's count of the cells past the grid instead of reading the keys: the
// count must be the number of kNotACellKey keys, wherever the grid ends in the scan.
TEST(CompactCellsTest, TheExpansionCountsTheCellsPastTheGrid) {
  const GridGeometry grid = Grid(10, 10, 1);
  for (const std::vector<uint64_t>& indices : std::vector<std::vector<uint64_t>>{
           {0, 1, 2, 3}, {97, 98, 99}, {98, 99, 100, 101}, {100, 101}, {5, 60, 99, 150}, {}}) {
    const CompactCells cells{EncodeIndexGaps(indices), PackOccupiedBits(std::vector<float>(indices.size(), 1.0f)), ""};
    UninitializedVector<uint64_t> keys;
    UninitializedVector<float> values;
    size_t outside = 12345;
    ASSERT_TRUE(ExpandCompactCells(grid, cells, 1 << 20, keys, values, &outside).ok());
    const size_t not_cells = static_cast<size_t>(std::count(keys.begin(), keys.end(), kNotACellKey));
    EXPECT_EQ(outside, not_cells) << indices.size() << " cells, the last " << (indices.empty() ? 0 : indices.back());
    EXPECT_EQ(not_cells, static_cast<size_t>(std::count_if(indices.begin(), indices.end(), [](uint64_t i) { return i >= 100; })));
  }
}

TEST(CompactCellsTest, ABatchLogsItsCompactBytesAndDecodesBackToThem) {
  MapInfo map;
  map.grid.size = {100, 100, 1};
  std::vector<uint64_t> indices;
  for (uint64_t i = 0; i < 10000; ++i) indices.push_back(3 * i / 2);
  ObservationBatch batch;
  batch.writer_id = 5;
  batch.sequence = 6;
  batch.time = 1.7e9;
  batch.compact = {EncodeIndexGaps(indices), PackOccupiedBits(std::vector<float>(indices.size(), 1.0f)), ""};
  ASSERT_TRUE(ExpandCompact(map, batch).ok());
  const std::string logged = EncodeBatch(batch);
  // ≤ 1.5 bytes per binary observation in the log: one byte of gap and one bit of value a cell.
  EXPECT_LE(logged.size(), indices.size() * 3 / 2);
  auto decoded = DecodeBatch(logged);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_TRUE(decoded->keys.empty());
  EXPECT_EQ(decoded->compact, batch.compact);
  ASSERT_TRUE(ExpandCompact(map, *decoded).ok());
  EXPECT_EQ(*decoded, batch);
  EXPECT_EQ(EncodeBatch(*decoded), logged);
  // A damaged compact record is DataLoss, never a crash.
  for (size_t cut = 0; cut < 40; ++cut) {
    EXPECT_EQ(DecodeBatch(std::string_view(logged).substr(0, cut)).status().code(), absl::StatusCode::kDataLoss);
  }
}

// The version 2 layout byte by byte (docs/storage.md, "Batch record"; fuzz/corpus/batch/batch_compact
// holds these bytes): a change of the format must be deliberate, old logs hold it.
TEST(CompactCellsTest, TheCompactRecordLayoutIsFixed) {
  ObservationBatch batch;
  batch.writer_id = 5;
  batch.sequence = 10;
  batch.time = 1.7e9;
  batch.compact = {std::string("\x03\x01\x01\x04", 4), std::string("\x0b", 1), ""};
  std::string want = std::string("\x02\x05\x0a", 3);
  const double time = 1.7e9;
  want.append(reinterpret_cast<const char*>(&time), 8);  // little-endian, as the log
  want += std::string("\x04\x03\x01\x01\x04", 5) + std::string("\x00\x01\x0b", 3) + std::string(7, '\0');
  EXPECT_EQ(EncodeBatch(batch), want);
}

}  // namespace
}  // namespace fremen::storage
