#include "storage/batch.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>

#include "storage/cell_key.h"
#include "storage/model/varint.h"

namespace fremen::storage {
namespace {

MapInfo Grid() {
  MapInfo info;
  info.name = "g";
  info.grid.size = {10, 10, 1};
  return info;
}

ObservationBatch Scan() {
  ObservationBatch batch;
  batch.writer_id = 7;
  batch.sequence = 99;
  batch.time = 1.7e9 + 0.25;
  for (uint32_t x = 0; x < 5; ++x) {
    batch.keys.push_back(Grid().grid.keys().Key(x, 2, 0));
    batch.values.push_back(x % 2 ? 1.0f : 0.0f);
  }
  batch.patch.origin = {1, 1, 0};
  batch.patch.size = {2, 3, 1};
  batch.patch.values = {0, 1, 0.5f, 1, 0, 1};
  return batch;
}

TEST(BatchTest, EncodingRoundTrips) {
  ObservationBatch batch = Scan();
  batch.keys.push_back(3);  // a key below the previous: negative delta
  batch.values.push_back(1);
  batch.labels.push_back({3, "kitchen door", "kitchen"});
  auto decoded = DecodeBatch(EncodeBatch(batch));
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, batch);
}

TEST(BatchTest, WholeBatchProblemsNameTheField) {
  const MapInfo map = Grid();
  ObservationBatch batch = Scan();
  batch.time = NAN;
  EXPECT_NE(ValidateBatch(map, batch).message().find("time"), std::string::npos);
  batch = Scan();
  batch.values.pop_back();
  EXPECT_NE(ValidateBatch(map, batch).message().find("values"), std::string::npos);
  batch = Scan();
  batch.patch.origin = {9, 0, 0};
  EXPECT_TRUE(absl::IsOutOfRange(ValidateBatch(map, batch)));
  batch = Scan();
  batch.patch.values.pop_back();
  EXPECT_NE(ValidateBatch(map, batch).message().find("patch.values"), std::string::npos);
  batch = Scan();
  batch.labels.push_back({1, "x", ""});
  EXPECT_NE(ValidateBatch(map, batch).message().find("labels"), std::string::npos);
  EXPECT_TRUE(ValidateBatch(map, Scan()).ok());
}

TEST(BatchTest, BadObservationsAreRejectedOneByOneWithReasons) {
  const MapInfo map = Grid();
  ObservationBatch batch = Scan();
  batch.values[1] = 1.5f;
  batch.keys[3] = uint64_t{12} | uint64_t{1} << 50;  // not a cell of this 2-D grid  // x outside the 10-cell grid
  batch.patch.values[4] = NAN;
  std::vector<uint8_t> accept;
  const BatchAck ack = Classify(map, batch, accept);
  EXPECT_EQ(ack.accepted, 8u);
  EXPECT_EQ(ack.rejected, 3u);
  ASSERT_EQ(ack.rejections.size(), 3u);
  EXPECT_EQ(ack.rejections[0].index, 1u);
  EXPECT_EQ(ack.rejections[0].reason, RejectReason::kValueOutOfRange);
  EXPECT_EQ(ack.rejections[1].index, 3u);
  EXPECT_EQ(ack.rejections[1].reason, RejectReason::kOutsideMap);
  EXPECT_EQ(ack.rejections[2].index, 5u + 4u);
  EXPECT_EQ(accept[9], 0);
  EXPECT_EQ(accept[0], 1);
}

TEST(BatchTest, DamagedBytesAreDataLossNeverACrash) {
  ObservationBatch with_label = Scan();
  const std::string good = EncodeBatch(with_label);
  for (size_t n = 0; n < good.size(); ++n) EXPECT_FALSE(DecodeBatch(good.substr(0, n)).ok()) << n;
  std::mt19937 rng(5);
  for (int i = 0; i < 5000; ++i) {
    std::string bytes = good;
    for (int flips = 0; flips < 3; ++flips) bytes[rng() % bytes.size()] ^= static_cast<char>(1 << (rng() % 8));
    (void)DecodeBatch(bytes);  // must not crash or over-allocate (ASan build)
  }
}

// Found with fuzz/batch_fuzz.cc (which aborts on these inputs without the fix): counts whose byte
// sizes wrap a uint64_t passed the "more than the bytes left" checks, and the decoder then tried to
// allocate up to 2^63 elements (std::length_error, the process ends).
TEST(BatchTest, CountsWhoseSizeWrapsAreDataLossNotAHugeAllocation) {
  ObservationBatch empty;
  empty.time = 1.7e9;
  const std::string good = EncodeBatch(empty);
  // version, writer, sequence, time (8 bytes): the key count follows at byte 11.
  const std::string head = good.substr(0, 11);
  std::string wrapping_keys = head;
  model::PutVarint64(&wrapping_keys, 0x3333333333333334);  // × 5 = 2^64 + 4
  wrapping_keys += std::string(16, '\0');
  auto keys = DecodeBatch(wrapping_keys);
  EXPECT_TRUE(absl::IsDataLoss(keys.status())) << keys.status();
  EXPECT_NE(keys.status().message().find("key count"), std::string::npos) << keys.status();

  std::string wrapping_patch = head;
  model::PutVarint64(&wrapping_patch, 0);                                     // no keys
  for (int a = 0; a < 3; ++a) model::PutVarint64(&wrapping_patch, 0);         // patch origin
  for (int a = 0; a < 3; ++a) model::PutVarint64(&wrapping_patch, 1u << 21);  // 2^63 cells, × 4 = 0 mod 2^64
  wrapping_patch += std::string(16, '\0');
  auto patch = DecodeBatch(wrapping_patch);
  EXPECT_TRUE(absl::IsDataLoss(patch.status())) << patch.status();
  EXPECT_NE(patch.status().message().find("patch.size"), std::string::npos) << patch.status();
}

MapInfo Generic() {
  MapInfo info;
  info.name = "states";
  info.kind = MapKind::kGeneric;
  return info;
}

// One door's history: a minute apart, a state change now and then, one time twice.
ObservationBatch History(size_t n) {
  ObservationBatch batch;
  batch.writer_id = 3;
  batch.sequence = 12;
  for (size_t i = 0; i < n; ++i) {
    batch.keys.push_back(42);
    batch.times.push_back(1.7e9 + 60.0 * static_cast<double>(i) + (i == 3 ? -60.0 : 0.0));
    batch.values.push_back((i / 7) % 2 ? 1.0f : 0.0f);
  }
  return batch;
}

TEST(BatchTest, HistoryEncodingRoundTripsBitExactly) {
  ObservationBatch batch = History(50);
  // Times no delta coding of floats would keep: going back, tiny steps, odd fractions, a jump.
  batch.times[10] = 0.0;
  batch.times[11] = std::nextafter(1.7e9, 2e9);
  batch.times[12] = 1.0 / 3.0;
  batch.times[13] = 1e13;
  batch.keys[20] = 7;  // another state in between
  batch.labels.push_back({42, "front door", "doors"});
  const std::string bytes = EncodeBatch(batch);
  EXPECT_EQ(bytes[0], 3) << "a history is version 3";
  auto decoded = DecodeBatch(bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, batch);
  for (size_t i = 0; i < batch.times.size(); ++i) {
    EXPECT_EQ(std::bit_cast<uint64_t>(decoded->times[i]), std::bit_cast<uint64_t>(batch.times[i])) << i;
  }
}

TEST(BatchTest, ScansStayVersion1SoTheirFingerprintsDoNotChange) {
  EXPECT_EQ(EncodeBatch(Scan())[0], 1);
  auto decoded = DecodeBatch(EncodeBatch(Scan()));
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_TRUE(decoded->times.empty());
}

TEST(BatchTest, OneStatesHistoryAMinuteApartTakesSixBytesAnObservation) {
  ObservationBatch batch = History(96'000);
  batch.times[3] = batch.times[2] + 60;  // steady throughout
  const std::string bytes = EncodeBatch(batch);
  // A key byte (delta 0), a float, and the time's second difference (0 at a steady rate, a byte)
  // instead of 8 bytes of double; the time's step changes at 2^31 s (a new binade): a few bytes.
  EXPECT_LE(bytes.size(), 6 * batch.keys.size() + 64) << bytes.size();
}

TEST(BatchTest, HistoryProblemsNameTheField) {
  const MapInfo map = Generic();
  EXPECT_TRUE(ValidateBatch(map, History(10)).ok());
  ObservationBatch batch = History(10);
  batch.times[4] = NAN;
  EXPECT_NE(ValidateBatch(map, batch).message().find("times[4]"), std::string::npos) << ValidateBatch(map, batch);
  batch.times[4] = -1;
  EXPECT_NE(ValidateBatch(map, batch).message().find("times[4]"), std::string::npos);
  batch.times[4] = 2e13;
  EXPECT_TRUE(absl::IsInvalidArgument(ValidateBatch(map, batch)));
  batch = History(10);
  batch.times.pop_back();
  EXPECT_NE(ValidateBatch(map, batch).message().find("times must hold one time per state"), std::string::npos);
  batch = History(10);
  batch.time = 5;
  EXPECT_NE(ValidateBatch(map, batch).message().find("time must be 0"), std::string::npos);
  EXPECT_NE(ValidateBatch(Grid(), History(10)).message().find("only for generic maps"), std::string::npos);
}

TEST(BatchTest, HistoryValuesOutOfRangeAreRejectedOneByOne) {
  ObservationBatch batch = History(10);
  batch.values[2] = 1.5f;
  batch.values[8] = NAN;
  std::vector<uint8_t> accept;
  const BatchAck ack = Classify(Generic(), batch, accept);
  EXPECT_EQ(ack.accepted, 8u);
  ASSERT_EQ(ack.rejections.size(), 2u);
  EXPECT_EQ(ack.rejections[0].index, 2u);
  EXPECT_EQ(ack.rejections[1].index, 8u);
}

TEST(BatchTest, DamagedHistoryBytesAreDataLoss) {
  const std::string good = EncodeBatch(History(20));
  for (size_t n = 0; n < good.size(); ++n) EXPECT_FALSE(DecodeBatch(good.substr(0, n)).ok()) << n;
  std::string extra = good + '\x01';
  EXPECT_TRUE(absl::IsDataLoss(DecodeBatch(extra).status()));
}

}  // namespace
}  // namespace fremen::storage
