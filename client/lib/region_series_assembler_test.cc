#include "client/lib/region_series_assembler.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::client {
namespace {

using ::testing::HasSubstr;

v1::PredictRegionSeriesResponse Chunk(uint64_t box, uint64_t varying, uint32_t times) {
  v1::PredictRegionSeriesResponse chunk;
  chunk.set_box_cells(box);
  chunk.set_varying_cells(varying);
  chunk.set_time_count(times);
  return chunk;
}

v1::PredictRegionSeriesResponse Base(uint64_t box, uint64_t varying, uint32_t times, uint64_t offset,
                                     uint64_t cells, std::string mask, std::vector<float> values) {
  v1::PredictRegionSeriesResponse chunk = Chunk(box, varying, times);
  chunk.set_base(true);
  chunk.set_offset(offset);
  chunk.set_cells(cells);
  chunk.set_varying_mask(std::move(mask));
  chunk.mutable_float_values()->Assign(values.begin(), values.end());
  return chunk;
}

v1::PredictRegionSeriesResponse Frame(uint64_t box, uint64_t varying, uint32_t times, uint32_t time,
                                      uint64_t offset, std::vector<float> values) {
  v1::PredictRegionSeriesResponse chunk = Chunk(box, varying, times);
  chunk.set_time_index(time);
  chunk.set_offset(offset);
  chunk.mutable_float_values()->Assign(values.begin(), values.end());
  return chunk;
}

// A 10-cell box: cells 1, 8 and 9 vary (mask bits 1 of byte 0, 0 and 1 of byte 1); two times.
TEST(RegionSeriesAssemblerTest, TheBaseOnceThenTheVaryingCellsPerTime) {
  RegionSeriesAssembler assembler({5, 2, 1}, v1::REGION_OUTPUT_FLOAT, 2);
  ASSERT_TRUE(assembler.Add(Base(10, 3, 2, 0, 8, "\x02", {0, 2, 3, 4, 5, 6, 7})).ok());
  ASSERT_TRUE(assembler.Add(Base(10, 3, 2, 8, 2, "\x03", {})).ok());
  ASSERT_TRUE(assembler.Add(Frame(10, 3, 2, 0, 0, {0.1f, 0.8f})).ok());
  ASSERT_TRUE(assembler.Add(Frame(10, 3, 2, 0, 2, {0.9f})).ok());
  ASSERT_TRUE(assembler.Add(Frame(10, 3, 2, 1, 0, {0.2f, 0.3f, 0.4f})).ok());
  auto series = assembler.Finish();
  ASSERT_TRUE(series.ok()) << series.status();
  ASSERT_EQ(series->frames.size(), 2u);
  EXPECT_EQ(series->varying_cells, 3u);
  EXPECT_EQ(series->values_received, 7u + 3 * 2);
  EXPECT_EQ(series->frames[0].floats, (std::vector<float>{0, 0.1f, 2, 3, 4, 5, 6, 7, 0.8f, 0.9f}));
  EXPECT_EQ(series->frames[1].floats, (std::vector<float>{0, 0.2f, 2, 3, 4, 5, 6, 7, 0.3f, 0.4f}));
  EXPECT_EQ(series->frames[1].shape, (GridShape{5, 2, 1}));
}

TEST(RegionSeriesAssemblerTest, NothingVaryingIsTheBaseAtEveryTime) {
  RegionSeriesAssembler assembler({3, 1, 1}, v1::REGION_OUTPUT_UINT8, 3);
  v1::PredictRegionSeriesResponse base = Chunk(3, 0, 3);
  base.set_base(true);
  base.set_cells(3);
  base.set_varying_mask(std::string(1, '\0'));
  base.set_bytes_values(std::string("\x01\x80\xff", 3));
  ASSERT_TRUE(assembler.Add(base).ok());
  auto series = assembler.Finish();
  ASSERT_TRUE(series.ok()) << series.status();
  ASSERT_EQ(series->frames.size(), 3u);
  EXPECT_EQ(series->frames[2].bytes, (std::vector<uint8_t>{1, 128, 255}));
  EXPECT_EQ(series->values_received, 3u);
}

TEST(RegionSeriesAssemblerTest, MisfitsAreDataLoss) {
  {  // values for a varying cell in the base
    RegionSeriesAssembler a({4, 1, 1}, v1::REGION_OUTPUT_FLOAT, 1);
    EXPECT_THAT(a.Add(Base(4, 1, 1, 0, 4, "\x01", {1, 2, 3, 4})).message(), HasSubstr("constant cells"));
  }
  {  // a frame before the base is complete
    RegionSeriesAssembler a({16, 1, 1}, v1::REGION_OUTPUT_FLOAT, 1);
    ASSERT_TRUE(a.Add(Base(16, 1, 1, 0, 8, "\x01", {1, 2, 3, 4, 5, 6, 7})).ok());
    EXPECT_TRUE(absl::IsDataLoss(a.Add(Frame(16, 1, 1, 0, 0, {0.5f}))));
  }
  {  // frames out of order, too many values, the wrong kind, the stream cut short
    RegionSeriesAssembler a({2, 1, 1}, v1::REGION_OUTPUT_FLOAT, 2);
    ASSERT_TRUE(a.Add(Base(2, 1, 2, 0, 2, "\x02", {7})).ok());
    EXPECT_TRUE(absl::IsDataLoss(a.Add(Frame(2, 1, 2, 1, 0, {0.5f}))));
    EXPECT_TRUE(absl::IsDataLoss(a.Add(Frame(2, 1, 2, 0, 0, {0.5f, 0.6f}))));
    v1::PredictRegionSeriesResponse bytes = Chunk(2, 1, 2);
    bytes.set_bytes_values("x");
    EXPECT_TRUE(absl::IsDataLoss(a.Add(bytes)));
    ASSERT_TRUE(a.Add(Frame(2, 1, 2, 0, 0, {0.5f})).ok());
    EXPECT_THAT(a.Finish().status().message(), HasSubstr("1 of 2 frames"));
  }
  {  // a chunk of another box
    RegionSeriesAssembler a({2, 1, 1}, v1::REGION_OUTPUT_FLOAT, 1);
    EXPECT_TRUE(absl::IsDataLoss(a.Add(Base(3, 0, 1, 0, 3, "\0", {1, 2, 3}))));
  }
}

}  // namespace
}  // namespace fremen::client
