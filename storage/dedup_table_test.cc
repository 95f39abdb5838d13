#include "storage/dedup_table.h"

#include <gtest/gtest.h>

#include <string>

namespace fremen::storage {
namespace {

TEST(DedupTableTest, TheSameBatchIsARetryAndOtherContentUnderItsSequenceIsRefused) {
  DedupTable table;
  for (uint64_t s = 1; s <= 10; ++s) table.Record(7, s, 1000 + s);
  EXPECT_EQ(table.LastSequence(7), 10u);
  EXPECT_EQ(table.LastSequence(8), 0u);
  EXPECT_EQ(table.Seen(7, 3, 1003).value(), true);
  // A rebooted writer counting from 1 again with new data.
  const absl::StatusOr<bool> reused = table.Seen(7, 3, 42);
  ASSERT_TRUE(absl::IsAlreadyExists(reused.status())) << reused.status();
  EXPECT_EQ(reused.status().message(),
            "writer 7 sequence 3 was already used for a different batch; continue after sequence 10");
  EXPECT_EQ(table.Seen(7, 11, 42).value(), false);
  EXPECT_EQ(table.Seen(8, 3, 42).value(), false);  // another writer's sequences are its own
}

TEST(DedupTableTest, AnUnusedSequenceBelowTheLastIsNewButOneBelowTheWindowIsRefused) {
  DedupTable table;
  table.Record(7, 20, 1);
  EXPECT_EQ(table.Seen(7, 15, 2).value(), false);  // a gap in the writer's count: never applied
  table.Record(7, 15, 2);
  EXPECT_EQ(table.LastSequence(7), 20u);  // the highest, not the latest
  EXPECT_EQ(table.Seen(7, 15, 2).value(), true);

  DedupTable many;
  const uint64_t last = DedupTable::kWindow + 100;
  for (uint64_t s = 1; s <= last; ++s) many.Record(1, s, s * 31);
  // The window holds the kWindow highest sequences; below it content is unknown.
  const uint64_t lowest = last - DedupTable::kWindow + 1;
  EXPECT_EQ(many.Seen(1, lowest, lowest * 31).value(), true);
  const absl::StatusOr<bool> forgotten = many.Seen(1, lowest - 1, (lowest - 1) * 31);
  ASSERT_TRUE(absl::IsAlreadyExists(forgotten.status())) << forgotten.status();
  EXPECT_NE(forgotten.status().message().find("writer 1 sequence " + std::to_string(lowest - 1)), std::string::npos);
  EXPECT_NE(forgotten.status().message().find("continue after sequence " + std::to_string(last)), std::string::npos);
  // Recording below the window (a replay of what a checkpoint has) changes nothing.
  DedupTable before = many;
  many.Record(1, 5, 5 * 31);
  EXPECT_EQ(many, before);
}

TEST(DedupTableTest, SequenceZeroIsASequenceLikeAnyOther) {
  DedupTable table;
  EXPECT_EQ(table.Seen(4, 0, 9).value(), false);
  table.Record(4, 0, 9);
  EXPECT_EQ(table.Seen(4, 0, 9).value(), true);
  EXPECT_TRUE(absl::IsAlreadyExists(table.Seen(4, 0, 10).status()));
  EXPECT_EQ(table.LastSequence(4), 0u);  // as for no batch: a writer's first sequence is then 1
  auto decoded = DedupTable::Decode(table.Encode());
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, table);
}

TEST(DedupTableTest, EncodingRoundTripsAndMergingTwoCheckpointsGivesTheLaterOne) {
  DedupTable early, late;
  for (uint64_t s = 1; s <= 100; ++s) early.Record(3, s, s ^ 0xabcdef);
  late = early;
  for (uint64_t s = 101; s <= DedupTable::kWindow + 150; ++s) late.Record(3, s, s ^ 0xabcdef);
  late.Record(1ull << 60, 9, 77);
  auto decoded = DedupTable::Decode(late.Encode());
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, late);
  EXPECT_EQ(decoded->writers(), 2u);

  DedupTable merged = early;
  merged.MergeFrom(late);
  EXPECT_EQ(merged, late);
  merged = late;
  merged.MergeFrom(early);
  EXPECT_EQ(merged, late);
  auto empty = DedupTable::Decode(DedupTable().Encode());
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->writers(), 0u);
}

TEST(DedupTableTest, DecodingIsStrict) {
  DedupTable table;
  table.Record(7, 1, 11);
  table.Record(7, 2, 12);
  table.Record(9, 5, 13);
  const std::string good = table.Encode();
  for (size_t n = 0; n < good.size(); ++n) {
    EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(good.substr(0, n)).status())) << "truncated to " << n;
  }
  EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(good + std::string(1, '\0')).status()));
  // Version 1 (no format byte: writer count, then pairs) is not taken for version 2.
  EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(std::string("\x01\x07\x0a", 3)).status()));
  // format 2, one writer 7, floor 0, two sequences: 0 (step 0 from the floor) and step 0 again.
  std::string zero_step("\x02\x01\x07\x00\x02\x00", 6);
  zero_step += std::string(8, '\x11');
  zero_step += '\x00';
  zero_step += std::string(8, '\x11');
  EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(zero_step).status()));
  // A writer with no sequence.
  EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(std::string("\x02\x01\x07\x00\x00", 5)).status()));
  // Writers out of order (9 then 7).
  std::string unordered("\x02\x02", 2);
  for (char writer : {'\x09', '\x07'}) {
    unordered += std::string({writer, '\x00', '\x01', '\x01'});
    unordered += std::string(8, '\x11');
  }
  EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(unordered).status()));
  // A count far beyond the bytes.
  EXPECT_TRUE(absl::IsDataLoss(DedupTable::Decode(std::string("\x02\xff\xff\x03", 4)).status()));
}

}  // namespace
}  // namespace fremen::storage
