#include "server/services/wire_chunk.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "fremen/v1/query.pb.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAreArray;

// The chunk's bytes as they go on the wire.
std::string WireBytes(const WireChunk& chunk) {
  std::vector<grpc::Slice> slices;
  EXPECT_TRUE(chunk.bytes.Dump(&slices).ok());
  std::string wire;
  for (const grpc::Slice& slice : slices) wire.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  return wire;
}

template <typename Message>
Message Parsed(const WireChunk& chunk) {
  Message message;
  EXPECT_TRUE(message.ParseFromString(WireBytes(chunk)));
  return message;
}

bool Aligned(const void* p) { return reinterpret_cast<uintptr_t>(p) % 64 == 0; }

TEST(ValuesInPlaceTest, BytesWrittenInPlaceParseAsTheMessagesBytesField) {
  v1::PredictRegionResponse fields;
  fields.set_offset(300);                      // a two-byte varint
  fields.set_box_cells(uint64_t{1} << 40);     // a six-byte one
  std::string values(1000, '\0');
  std::mt19937 random(7);
  for (char& c : values) c = static_cast<char>(random());
  ValuesInPlace chunk(fields, v1::PredictRegionResponse::kBytesValuesFieldNumber, values.size());
  ASSERT_EQ(chunk.bytes().size(), values.size());
  EXPECT_TRUE(Aligned(chunk.bytes().data()));
  std::memcpy(chunk.bytes().data(), values.data(), values.size());
  const WireChunk wire = std::move(chunk).Finish(values.size());
  EXPECT_EQ(wire.values, values.size());

  const auto parsed = Parsed<v1::PredictRegionResponse>(wire);
  EXPECT_EQ(parsed.offset(), 300u);
  EXPECT_EQ(parsed.box_cells(), uint64_t{1} << 40);
  EXPECT_EQ(parsed.bytes_values(), values);
  EXPECT_EQ(parsed.float_values_size(), 0);
  // Byte for byte what protobuf writes (the values field is the last by number, so the same order).
  v1::PredictRegionResponse whole = fields;
  whole.set_bytes_values(values);
  EXPECT_EQ(WireBytes(wire), whole.SerializeAsString());
}

TEST(ValuesInPlaceTest, FloatsWrittenInPlaceParseBitForBit) {
  v1::PredictRegionSeriesResponse fields;  // the values field after others set, bytes among them
  fields.set_box_cells(4096);
  fields.set_base(true);
  fields.set_varying_mask(std::string("\x05\x00\xff", 3));
  const std::vector<float> values = {0.0f, -0.0f, 0.5f, 1.0f, std::numeric_limits<float>::denorm_min(),
                                     std::nextafter(1.0f, 0.0f), 1e-30f, std::numeric_limits<float>::quiet_NaN()};
  ValuesInPlace chunk(fields, v1::PredictRegionSeriesResponse::kFloatValuesFieldNumber,
                      values.size() * sizeof(float));
  ASSERT_EQ(chunk.floats().size(), values.size());
  EXPECT_TRUE(Aligned(chunk.floats().data()));
  std::copy(values.begin(), values.end(), chunk.floats().begin());
  const auto parsed = Parsed<v1::PredictRegionSeriesResponse>(std::move(chunk).Finish(values.size()));

  EXPECT_EQ(parsed.box_cells(), 4096u);
  EXPECT_TRUE(parsed.base());
  EXPECT_EQ(parsed.varying_mask(), fields.varying_mask());
  ASSERT_EQ(parsed.float_values_size(), static_cast<int>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) {
    EXPECT_EQ(std::bit_cast<uint32_t>(parsed.float_values(static_cast<int>(i))), std::bit_cast<uint32_t>(values[i]))
        << "value " << i;
  }
}

TEST(ValuesInPlaceTest, NoOtherFieldsAndNoValues) {
  // Fields at their defaults are not on the wire: the message is the values' tag and length.
  const v1::PredictRegionResponse none;
  ValuesInPlace empty(none, v1::PredictRegionResponse::kFloatValuesFieldNumber, 0);
  const WireChunk wire = std::move(empty).Finish(0);
  EXPECT_EQ(WireBytes(wire), std::string("\x1a\x00", 2));  // field 3, length-delimited; length 0
  const auto parsed = Parsed<v1::PredictRegionResponse>(wire);
  EXPECT_EQ(parsed.offset(), 0u);
  EXPECT_EQ(parsed.float_values_size(), 0);

  // A long run's length takes three bytes; the values still start aligned.
  ValuesInPlace big(none, v1::PredictRegionResponse::kBytesValuesFieldNumber, 1 << 20);
  EXPECT_TRUE(Aligned(big.bytes().data()));
  std::memset(big.bytes().data(), 0x80, big.bytes().size());
  EXPECT_EQ(Parsed<v1::PredictRegionResponse>(std::move(big).Finish(1 << 20)).bytes_values(),
            std::string(1 << 20, '\x80'));
}

TEST(ValuesInPlaceTest, AnUnfinishedChunkFreesItsRoom) {
  // Under ASan a leak here fails the run; the chunk is dropped as when a prediction fails.
  const v1::PredictRegionResponse none;
  ValuesInPlace dropped(none, v1::PredictRegionResponse::kBytesValuesFieldNumber, 4096);
  dropped.bytes()[0] = 1;
}

TEST(SerializedChunkTest, IsTheMessageAndCarriesItsCount) {
  v1::PredictRegionResponse message;
  message.set_offset(5);
  message.add_float_values(0.25f);
  message.add_float_values(0.75f);
  const absl::StatusOr<WireChunk> chunk = SerializedChunk(message, 2);
  ASSERT_TRUE(chunk.ok()) << chunk.status();
  EXPECT_EQ(chunk->values, 2u);
  const auto parsed = Parsed<v1::PredictRegionResponse>(*chunk);
  EXPECT_EQ(parsed.offset(), 5u);
  EXPECT_THAT(parsed.float_values(), ElementsAreArray({0.25f, 0.75f}));
}

}  // namespace
}  // namespace fremen::server
