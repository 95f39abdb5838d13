#include "client/lib/region_assembler.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::client {
namespace {

using ::testing::HasSubstr;

v1::PredictRegionResponse FloatChunk(uint64_t offset, uint64_t box, std::vector<float> values) {
  v1::PredictRegionResponse chunk;
  chunk.set_offset(offset);
  chunk.set_box_cells(box);
  chunk.mutable_float_values()->Assign(values.begin(), values.end());
  return chunk;
}

v1::PredictRegionResponse ByteChunk(uint64_t offset, uint64_t box, std::string bytes) {
  v1::PredictRegionResponse chunk;
  chunk.set_offset(offset);
  chunk.set_box_cells(box);
  chunk.set_bytes_values(std::move(bytes));
  return chunk;
}

TEST(RegionAssemblerTest, ChunksMakeTheBoxXFastest) {
  RegionAssembler assembler({3, 2, 2}, v1::REGION_OUTPUT_FLOAT);
  ASSERT_TRUE(assembler.Add(FloatChunk(0, 12, {0, 1, 2, 3, 4})).ok());
  ASSERT_TRUE(assembler.Add(FloatChunk(5, 12, {5, 6, 7, 8, 9, 10, 11})).ok());
  auto array = assembler.Finish();
  ASSERT_TRUE(array.ok()) << array.status();
  EXPECT_EQ(array->shape, (GridShape{3, 2, 2}));
  EXPECT_TRUE(array->is_float());
  EXPECT_EQ(array->floats[array->Index(2, 0, 0)], 2);
  EXPECT_EQ(array->floats[array->Index(0, 1, 0)], 3);
  EXPECT_EQ(array->floats[array->Index(2, 1, 1)], 11);
}

TEST(RegionAssemblerTest, BytesForUint8AndStates) {
  RegionAssembler assembler({2, 2, 1}, v1::REGION_OUTPUT_UINT8);
  ASSERT_TRUE(assembler.Add(ByteChunk(0, 4, std::string("\x00\x10\x20\xff", 4))).ok());
  auto array = assembler.Finish();
  ASSERT_TRUE(array.ok()) << array.status();
  EXPECT_FALSE(array->is_float());
  EXPECT_EQ(array->bytes[array->Index(1, 1)], 255);
  RegionAssembler states({1, 1, 1}, v1::REGION_OUTPUT_STATES);
  ASSERT_TRUE(states.Add(ByteChunk(0, 1, std::string("\x01", 1))).ok());
  EXPECT_EQ(states.Finish()->bytes[0], 1);
}

TEST(RegionAssemblerTest, UnspecifiedOutputIsFloat) {
  RegionAssembler assembler({1, 1, 1}, v1::REGION_OUTPUT_UNSPECIFIED);
  ASSERT_TRUE(assembler.Add(FloatChunk(0, 1, {0.5f})).ok());
  EXPECT_EQ(assembler.Finish()->output, v1::REGION_OUTPUT_FLOAT);
}

TEST(RegionAssemblerTest, GapOverlapAndOverflowAreDataLoss) {
  RegionAssembler gap({4, 1, 1}, v1::REGION_OUTPUT_FLOAT);
  ASSERT_TRUE(gap.Add(FloatChunk(0, 4, {0, 1})).ok());
  absl::Status skipped = gap.Add(FloatChunk(3, 4, {3}));
  EXPECT_EQ(skipped.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(skipped.message(), HasSubstr("offset 3 where 2 was expected"));
  EXPECT_EQ(gap.Add(FloatChunk(1, 4, {1})).code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(gap.Add(FloatChunk(2, 4, {2, 3, 4})).message(), HasSubstr("does not fit"));
}

TEST(RegionAssemblerTest, WrongBoxSizeAndWrongValueKindAreDataLoss) {
  RegionAssembler assembler({2, 1, 1}, v1::REGION_OUTPUT_FLOAT);
  EXPECT_THAT(assembler.Add(FloatChunk(0, 3, {0, 1})).message(), HasSubstr("box has 3 cells, not 2"));
  EXPECT_THAT(assembler.Add(ByteChunk(0, 2, "ab")).message(), HasSubstr("another output kind"));
}

TEST(RegionAssemblerTest, MissingCellsAreDataLoss) {
  RegionAssembler assembler({3, 1, 1}, v1::REGION_OUTPUT_FLOAT);
  ASSERT_TRUE(assembler.Add(FloatChunk(0, 3, {0, 1})).ok());
  auto array = assembler.Finish();
  EXPECT_EQ(array.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(array.status().message(), HasSubstr("after 2 of 3 cells"));
}

}  // namespace
}  // namespace fremen::client
