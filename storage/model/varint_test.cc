#include "storage/model/varint.h"

#include <cstdint>
#include <limits>
#include <random>
#include <string>

#include "gtest/gtest.h"

namespace fremen::model {
namespace {

// One varint from the front of *in, advancing past it, through the decoders' ByteReader; *in is
// unchanged on error.
absl::StatusOr<uint64_t> ReadVarint(std::string_view* in) {
  ByteReader reader(*in, "test");
  const uint64_t v = reader.Varint("v");
  if (!reader.ok()) return reader.status();
  in->remove_prefix(reader.offset());
  return v;
}

TEST(Varint, RoundTripsEdgeValues) {
  const uint64_t values[] = {0,           1,           127,         128,         16383, 16384, (1u << 21) - 1,
                             1u << 21,    0xffffffffu, 1ull << 32,  1ull << 56,  1ull << 63,
                             std::numeric_limits<uint64_t>::max()};
  for (uint64_t v : values) {
    std::string bytes;
    PutVarint64(&bytes, v);
    EXPECT_EQ(bytes.size(), Varint64Length(v)) << v;
    bytes += "tail";
    std::string_view in = bytes;
    absl::StatusOr<uint64_t> got = ReadVarint(&in);
    ASSERT_TRUE(got.ok()) << got.status();
    EXPECT_EQ(*got, v);
    EXPECT_EQ(in, "tail");
  }
  EXPECT_EQ(Varint64Length(0), 1u);
  EXPECT_EQ(Varint64Length(127), 1u);
  EXPECT_EQ(Varint64Length(128), 2u);
  EXPECT_EQ(Varint64Length(std::numeric_limits<uint64_t>::max()), 10u);
}

TEST(Varint, KnownEncoding) {
  std::string bytes;
  PutVarint64(&bytes, 300);
  EXPECT_EQ(bytes, std::string("\xac\x02", 2));
}

TEST(Varint, RejectsTruncatedInputAndLeavesItUnchanged) {
  std::string bytes;
  PutVarint64(&bytes, 1ull << 40);
  for (size_t n = 0; n < bytes.size(); ++n) {
    std::string_view in(bytes.data(), n);
    absl::StatusOr<uint64_t> got = ReadVarint(&in);
    ASSERT_FALSE(got.ok()) << n;
    EXPECT_EQ(got.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_EQ(in.size(), n);
  }
}

TEST(Varint, RejectsOverlongInput) {
  // Eleven continuation bytes never end within 64 bits.
  const std::string eleven(11, '\x80');
  std::string_view in = eleven;
  EXPECT_EQ(ReadVarint(&in).status().code(), absl::StatusCode::kDataLoss);
  // Ten bytes whose last holds more than bit 63.
  std::string ten(9, '\xff');
  ten.push_back('\x02');
  in = ten;
  EXPECT_EQ(ReadVarint(&in).status().code(), absl::StatusCode::kDataLoss);
  // The largest value is fine.
  ten.back() = '\x01';
  in = ten;
  EXPECT_EQ(*ReadVarint(&in), std::numeric_limits<uint64_t>::max());
}

TEST(Varint, RejectsNonCanonicalInput) {
  const std::string padded("\x80\x00", 2);  // 0 in two bytes
  std::string_view in = padded;
  EXPECT_EQ(ReadVarint(&in).status().code(), absl::StatusCode::kDataLoss);
  const std::string padded_one("\x81\x80\x00", 3);
  in = padded_one;
  EXPECT_EQ(ReadVarint(&in).status().code(), absl::StatusCode::kDataLoss);
}

TEST(Varint, RandomBytesNeverCrashAndDecodedValuesReencodeToTheSameBytes) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20000; ++trial) {
    std::string bytes(rng() % 12, '\0');
    for (char& c : bytes) c = static_cast<char>(rng() % 4 == 0 ? rng() : (rng() | 0x80));
    std::string_view in = bytes;
    absl::StatusOr<uint64_t> got = ReadVarint(&in);
    if (!got.ok()) continue;
    std::string again;
    PutVarint64(&again, *got);
    EXPECT_EQ(again, bytes.substr(0, bytes.size() - in.size()));
  }
}

TEST(Varint, ZigZagMapsSmallMagnitudesToSmallValues) {
  EXPECT_EQ(ZigZagEncode64(0), 0u);
  EXPECT_EQ(ZigZagEncode64(-1), 1u);
  EXPECT_EQ(ZigZagEncode64(1), 2u);
  EXPECT_EQ(ZigZagEncode64(-2), 3u);
  EXPECT_EQ(ZigZagEncode64(std::numeric_limits<int64_t>::max()), std::numeric_limits<uint64_t>::max() - 1);
  EXPECT_EQ(ZigZagEncode64(std::numeric_limits<int64_t>::min()), std::numeric_limits<uint64_t>::max());
  for (int64_t v : {int64_t{0}, int64_t{1}, int64_t{-1}, int64_t{12345}, int64_t{-987654321},
                    std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::min()}) {
    EXPECT_EQ(ZigZagDecode64(ZigZagEncode64(v)), v);
  }
}

TEST(Varint, FixedWidthValuesAreLittleEndian) {
  std::string bytes;
  PutFixed32(&bytes, 0x04030201u);
  PutFixed64(&bytes, 0x0807060504030201ull);
  EXPECT_EQ(bytes, std::string("\x01\x02\x03\x04\x01\x02\x03\x04\x05\x06\x07\x08", 12));
  PutFloat(&bytes, -1.5f);
  PutDouble(&bytes, 0.1);
  ByteReader reader(bytes, "test");
  EXPECT_EQ(reader.Fixed32("a"), 0x04030201u);
  EXPECT_EQ(reader.Fixed64("b"), 0x0807060504030201ull);
  EXPECT_EQ(reader.Float("c"), -1.5f);
  EXPECT_EQ(reader.Double("d"), 0.1);
  EXPECT_TRUE(reader.Finish().ok());
}

TEST(Varint, FixedWidthValuesInRawBytesAreLittleEndianToo) {
  unsigned char bytes[12] = {};
  EncodeFixed32(bytes, 0x04030201u);
  EncodeFixed64(bytes + 4, 0x0807060504030201ull);
  const unsigned char want[12] = {1, 2, 3, 4, 1, 2, 3, 4, 5, 6, 7, 8};
  EXPECT_EQ(std::string(reinterpret_cast<char*>(bytes), 12), std::string(reinterpret_cast<const char*>(want), 12));
  EXPECT_EQ(DecodeFixed32(bytes), 0x04030201u);
  EXPECT_EQ(DecodeFixed64(bytes + 4), 0x0807060504030201ull);
  // High bytes survive (no sign extension through char).
  EncodeFixed64(bytes, 0xfffefdfcfbfaf9f8ull);
  EXPECT_EQ(DecodeFixed64(bytes), 0xfffefdfcfbfaf9f8ull);
  EXPECT_EQ(DecodeFixed32(bytes + 4), 0xfffefdfcu);
}

TEST(Varint, ByteReaderErrorsAreStickyAndNameTheField) {
  std::string bytes;
  PutVarint64(&bytes, 5);
  bytes.push_back('\x80');  // a truncated varint
  ByteReader reader(bytes, "record");
  EXPECT_EQ(reader.Varint("count"), 5u);
  EXPECT_EQ(reader.Varint("size"), 0u);
  EXPECT_FALSE(reader.ok());
  EXPECT_EQ(reader.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_NE(reader.status().message().find("record: size: truncated varint (at byte 1)"), std::string::npos)
      << reader.status();
  // Later reads neither read nor replace the first error.
  EXPECT_EQ(reader.Fixed64("later"), 0u);
  EXPECT_NE(reader.status().message().find("size"), std::string::npos);
}

TEST(Varint, ByteReaderRejectsShortFixedWidthReadsAndTrailingBytes) {
  ByteReader short_reader(std::string_view("abc"), "record");
  EXPECT_EQ(short_reader.Fixed32("word"), 0u);
  EXPECT_NE(short_reader.status().message().find("needs 4 bytes, 3 left"), std::string::npos);

  ByteReader long_reader(std::string_view("abc"), "record");
  EXPECT_EQ(long_reader.Byte("first"), 'a');
  const absl::Status s = long_reader.Finish();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_NE(s.message().find("2 unexpected trailing bytes"), std::string::npos) << s;

  ByteReader huge(std::string_view("abc"), "record");
  EXPECT_TRUE(huge.Bytes(std::numeric_limits<uint64_t>::max(), "blob").empty());
  EXPECT_FALSE(huge.ok());
}

}  // namespace
}  // namespace fremen::model
