#include "storage/wal/wal.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "storage/testing/file_damage.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

std::vector<uint8_t> Payload(uint64_t i) {
  std::vector<uint8_t> p(1 + i % 300);
  for (size_t j = 0; j < p.size(); ++j) p[j] = static_cast<uint8_t>(i * 31 + j);
  return p;
}

std::vector<uint64_t> ReplayAll(const std::string& dir, uint64_t after, WalReplayResult* result = nullptr) {
  std::vector<uint64_t> lsns;
  auto r = ReplayWal(dir, after, [&](uint64_t lsn, std::span<const uint8_t> payload) {
    const auto expected = Payload(lsn);
    const bool same = std::equal(payload.begin(), payload.end(), expected.begin(), expected.end());
    EXPECT_TRUE(same) << lsn;
    lsns.push_back(lsn);
    return absl::OkStatus();
  });
  EXPECT_TRUE(r.ok()) << r.status();
  if (result && r.ok()) *result = *r;
  return lsns;
}

// Appends records first..last, each synced (so that segments roll at options.segment_bytes).
void AppendSynced(const std::string& dir, const WalOptions& options, uint64_t first, uint64_t last) {
  auto wal = WalWriter::Open(dir, options);
  ASSERT_TRUE(wal.ok()) << wal.status();
  for (uint64_t i = first; i <= last; ++i) {
    ASSERT_EQ((*wal)->Append(Payload(i)), i);
    ASSERT_TRUE((*wal)->Sync().ok());
  }
}

TEST(WalTest, ReplaysWhatWasSyncedInOrderAfterAGivenLsn) {
  fremen::testing::TempDir dir;
  {
    auto wal = WalWriter::Open(dir.path(), {});
    ASSERT_TRUE(wal.ok()) << wal.status();
    for (uint64_t i = 1; i <= 100; ++i) {
      EXPECT_EQ((*wal)->Append(Payload(i)), i);
      if (i % 7 == 0) {
        ASSERT_TRUE((*wal)->Sync().ok());
      }
    }
    ASSERT_TRUE((*wal)->Sync().ok());
    EXPECT_EQ((*wal)->durable_lsn(), 100u);
  }
  EXPECT_EQ(ReplayAll(dir.path(), 0).size(), 100u);
  const auto tail = ReplayAll(dir.path(), 90);
  ASSERT_EQ(tail.size(), 10u);
  EXPECT_EQ(tail.front(), 91u);
  // Reopening continues the LSN sequence.
  auto wal = WalWriter::Open(dir.path(), {});
  ASSERT_TRUE(wal.ok());
  EXPECT_EQ((*wal)->Append(Payload(101)), 101u);
  ASSERT_TRUE((*wal)->Sync().ok());
  EXPECT_EQ(ReplayAll(dir.path(), 0).size(), 101u);
}

TEST(WalTest, UnsyncedRecordsAreNotDurable) {
  fremen::testing::TempDir dir;
  {
    auto wal = WalWriter::Open(dir.path(), {});
    ASSERT_TRUE(wal.ok());
    (*wal)->Append(Payload(1));
    ASSERT_TRUE((*wal)->Sync().ok());
    (*wal)->Append(Payload(2));  // never synced: gone with the process
  }
  EXPECT_EQ(ReplayAll(dir.path(), 0), std::vector<uint64_t>{1});
}

TEST(WalTest, ATornTailIsCutAndTheLogGoesOn) {
  fremen::testing::TempDir dir;
  std::string segment;
  {
    auto wal = WalWriter::Open(dir.path(), {});
    ASSERT_TRUE(wal.ok());
    for (uint64_t i = 1; i <= 20; ++i) (*wal)->Append(Payload(i));
    ASSERT_TRUE((*wal)->Sync().ok());
  }
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) segment = e.path();
  const auto size = std::filesystem::file_size(segment);
  std::filesystem::resize_file(segment, size - 5);  // the last record loses its end
  WalReplayResult result;
  EXPECT_EQ(ReplayAll(dir.path(), 0, &result).size(), 19u);
  EXPECT_TRUE(result.truncated_tail);
  EXPECT_EQ(result.torn_tail_file, segment);
  EXPECT_EQ(result.torn_tail_bytes, 16 + Payload(20).size() - 5);
  EXPECT_EQ(result.torn_tail_offset, size - (16 + Payload(20).size()));
  auto wal = WalWriter::Open(dir.path(), {});
  ASSERT_TRUE(wal.ok()) << wal.status();
  EXPECT_EQ((*wal)->Append(Payload(20)), 20u);
  ASSERT_TRUE((*wal)->Sync().ok());
  EXPECT_EQ(ReplayAll(dir.path(), 0, &result).size(), 20u);
  EXPECT_FALSE(result.truncated_tail);
}

TEST(WalTest, AWriterOpenedAfterItsReplayTakesTheNewestSegmentFromItAndCutsTheTornTail) {
  fremen::testing::TempDir dir;
  WalOptions small;
  small.segment_bytes = 2000;  // several segments: the replay's newest one is what the writer uses
  AppendSynced(dir.path(), small, 1, 60);
  std::string newest;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) newest = std::max(newest, e.path().string());
  const auto size = std::filesystem::file_size(newest);
  std::filesystem::resize_file(newest, size - 3);  // the last record loses its end
  WalReplayResult replayed;
  ASSERT_EQ(ReplayAll(dir.path(), 0, &replayed).size(), 59u);
  ASSERT_TRUE(replayed.newest_segment_scanned);
  EXPECT_EQ(replayed.newest_segment_intact_bytes, size - (16 + Payload(60).size()));
  // Damage the newest segment's first record after the replay: a writer that read the segment again
  // would find corruption; one that takes the replay's scan opens where the replay stopped.
  {
    std::fstream f(newest, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(20);
    f.put('\x5a');
  }
  WalOptions options = small;
  options.replayed = &replayed;
  auto wal = WalWriter::Open(dir.path(), options);
  ASSERT_TRUE(wal.ok()) << wal.status();
  EXPECT_EQ(std::filesystem::file_size(newest), replayed.newest_segment_intact_bytes);  // the tail is cut
  EXPECT_EQ((*wal)->Append(Payload(60)), 60u);
  ASSERT_TRUE((*wal)->Sync().ok());
  // Without the replay's scan the writer reads the segment itself and finds the damage.
  wal->reset();
  EXPECT_EQ(WalWriter::Open(dir.path(), small).status().code(), absl::StatusCode::kDataLoss);
}

TEST(WalTest, AReplayOfAnotherNewestSegmentIsNotTakenByTheWriter) {
  fremen::testing::TempDir dir;
  WalOptions small;
  small.segment_bytes = 2000;
  AppendSynced(dir.path(), small, 1, 10);
  WalReplayResult stale;
  ASSERT_EQ(ReplayAll(dir.path(), 0, &stale).size(), 10u);
  AppendSynced(dir.path(), small, 11, 60);  // rolls into new segments
  ASSERT_TRUE(stale.newest_segment_scanned);
  WalOptions options = small;
  options.replayed = &stale;  // names a segment that is no longer the newest
  auto wal = WalWriter::Open(dir.path(), options);
  ASSERT_TRUE(wal.ok()) << wal.status();
  EXPECT_EQ((*wal)->Append(Payload(61)), 61u);
  ASSERT_TRUE((*wal)->Sync().ok());
  EXPECT_EQ(ReplayAll(dir.path(), 0).size(), 61u);
}

TEST(WalTest, SegmentsRollAndCheckpointedOnesAreDropped) {
  fremen::testing::TempDir dir;
  WalOptions options;
  options.segment_bytes = 2000;
  auto wal = WalWriter::Open(dir.path(), options);
  ASSERT_TRUE(wal.ok());
  for (uint64_t i = 1; i <= 200; ++i) {
    (*wal)->Append(Payload(i));
    ASSERT_TRUE((*wal)->Sync().ok());
  }
  const auto files = [&] {
    return std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator());
  };
  const auto before = files();
  EXPECT_GT(before, 5);
  const uint64_t bytes_before = (*wal)->bytes();
  ASSERT_TRUE((*wal)->DropThrough(150).ok());
  EXPECT_LT(files(), before);
  EXPECT_LT((*wal)->bytes(), bytes_before);
  const auto rest = ReplayAll(dir.path(), 150);
  ASSERT_EQ(rest.size(), 50u);
  EXPECT_EQ(rest.front(), 151u);
}

TEST(WalTest, CorruptionBeforeTheTailIsDataLoss) {
  fremen::testing::TempDir dir;
  WalOptions options;
  options.segment_bytes = 1000;
  {
    auto wal = WalWriter::Open(dir.path(), options);
    ASSERT_TRUE(wal.ok());
    for (uint64_t i = 1; i <= 50; ++i) {
      (*wal)->Append(Payload(i));
      ASSERT_TRUE((*wal)->Sync().ok());
    }
  }
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) segments.push_back(e.path());
  std::sort(segments.begin(), segments.end());
  ASSERT_GT(segments.size(), 2u);
  {
    std::fstream f(segments[0], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(20);
    f.put('\xff');
  }
  auto replay = ReplayWal(dir.path(), 0, [](uint64_t, auto) { return absl::OkStatus(); });
  ASSERT_FALSE(replay.ok());
  EXPECT_TRUE(absl::IsDataLoss(replay.status())) << replay.status();
  // The writer reads only the last segment: it opens, and recovery is what reports the damage.
  auto writer = WalWriter::Open(dir.path(), options);
  ASSERT_TRUE(writer.ok());
  EXPECT_EQ((*writer)->Append(Payload(51)), 51u);
}

std::vector<std::string> Segments(const std::string& dir) {
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(dir)) segments.push_back(e.path());
  std::sort(segments.begin(), segments.end());
  return segments;
}

using testing::OverwriteBytes;
using testing::ReadWholeFile;

// Writes records 1..n, each synced, into one segment.
void WriteRecords(const std::string& dir, uint64_t n) {
  auto wal = WalWriter::Open(dir, {});
  ASSERT_TRUE(wal.ok()) << wal.status();
  for (uint64_t i = 1; i <= n; ++i) {
    (*wal)->Append(Payload(i));
    ASSERT_TRUE((*wal)->Sync().ok());
  }
}

// Before the torn-tail rule (storage/README.md, "Torn tail and corruption"): a bad record of the
// last segment was taken for a torn tail, and everything after it was cut.
TEST(WalTest, CorruptionIsNotATornTailAMidSegmentFlipIsDataLossAndNothingIsCut) {
  fremen::testing::TempDir dir;
  WriteRecords(dir.path(), 40);
  const std::string segment = Segments(dir.path()).front();
  uint64_t offset = 0;  // of record 20
  for (uint64_t i = 1; i < 20; ++i) offset += 16 + Payload(i).size();
  OverwriteBytes(segment, offset + 3, std::string(16, '\x5a'));  // 16 bytes flipped in its header and payload
  const std::string damaged = ReadWholeFile(segment);
  auto replay = ReplayWal(dir.path(), 0, [](uint64_t, auto) { return absl::OkStatus(); });
  ASSERT_FALSE(replay.ok());
  EXPECT_TRUE(absl::IsDataLoss(replay.status())) << replay.status();
  const std::string message(replay.status().message());
  EXPECT_NE(message.find(segment), std::string::npos) << message;
  EXPECT_NE(message.find(absl::StrCat("byte ", offset)), std::string::npos) << message;
  EXPECT_NE(message.find("LSN 20"), std::string::npos) << message;
  // The writer refuses too, and cuts nothing.
  auto writer = WalWriter::Open(dir.path(), {});
  ASSERT_FALSE(writer.ok());
  EXPECT_TRUE(absl::IsDataLoss(writer.status())) << writer.status();
  EXPECT_EQ(ReadWholeFile(segment), damaged);
  EXPECT_EQ(Segments(dir.path()).size(), 1u);
}

TEST(WalTest, AnIntactRecordOutOfSequenceIsCorruption) {
  fremen::testing::TempDir dir;
  WriteRecords(dir.path(), 3);
  fremen::testing::TempDir other;
  WriteRecords(other.path(), 5);
  // Record 5 of another log appended: intact, but LSN 5 where 4 is due.
  const std::string foreign = ReadWholeFile(Segments(other.path()).front());
  uint64_t offset = 0;
  for (uint64_t i = 1; i < 5; ++i) offset += 16 + Payload(i).size();
  std::ofstream(Segments(dir.path()).front(), std::ios::binary | std::ios::app) << foreign.substr(offset);
  auto replay = ReplayWal(dir.path(), 0, [](uint64_t, auto) { return absl::OkStatus(); });
  ASSERT_FALSE(replay.ok());
  EXPECT_TRUE(absl::IsDataLoss(replay.status())) << replay.status();
  EXPECT_FALSE(WalWriter::Open(dir.path(), {}).ok());
}

// Judged a torn tail: a crash can leave the file's size written and its last page not (zeros), or a
// last record half old bytes; nothing after it was ever acknowledged.
TEST(WalTest, ALastRecordWithABadCrcOrZerosAtTheEndIsATornTail) {
  for (const bool zeros : {false, true}) {
    fremen::testing::TempDir dir;
    WriteRecords(dir.path(), 10);
    const std::string segment = Segments(dir.path()).front();
    const uint64_t size = std::filesystem::file_size(segment);
    if (zeros) {
      std::filesystem::resize_file(segment, size + 4096);
    } else {
      OverwriteBytes(segment, size - 2, "\x01\x02");  // in the last record's payload
    }
    WalReplayResult result;
    EXPECT_EQ(ReplayAll(dir.path(), 0, &result).size(), zeros ? 10u : 9u) << zeros;
    EXPECT_TRUE(result.truncated_tail);
    EXPECT_EQ(result.torn_tail_bytes, zeros ? 4096 : 16 + Payload(10).size());
    auto wal = WalWriter::Open(dir.path(), {});
    ASSERT_TRUE(wal.ok()) << wal.status();
    EXPECT_EQ((*wal)->last_lsn(), zeros ? 10u : 9u);
    EXPECT_EQ(std::filesystem::file_size(segment), zeros ? size : size - 16 - Payload(10).size());
  }
}

// Before the LSN floor (storage/README.md, "Torn tail and corruption"): the writer resumed below
// the shards' checkpoint LSN, and a later recovery skipped the new records as checkpointed.
TEST(WalTest, TheWriterNeverGoesBelowItsLsnFloor) {
  fremen::testing::TempDir dir;
  WriteRecords(dir.path(), 10);
  WalOptions options;
  options.min_next_lsn = 31;  // a checkpoint at LSN 30, and the log lost its records 11..30
  {
    auto wal = WalWriter::Open(dir.path(), options);
    ASSERT_TRUE(wal.ok()) << wal.status();
    EXPECT_EQ((*wal)->last_lsn(), 30u);
    EXPECT_EQ((*wal)->Append(Payload(31)), 31u);
    ASSERT_TRUE((*wal)->Sync().ok());
  }
  const auto segments = Segments(dir.path());
  ASSERT_EQ(segments.size(), 2u);
  EXPECT_NE(segments.back().find("wal-00000000000000000031.log"), std::string::npos) << segments.back();
  // The gap lies below the checkpoint: replay after it goes on; a replay that needs the gap fails.
  EXPECT_EQ(ReplayAll(dir.path(), 30), std::vector<uint64_t>{31});
  auto needs_gap = ReplayWal(dir.path(), 20, [](uint64_t, auto) { return absl::OkStatus(); });
  ASSERT_FALSE(needs_gap.ok());
  EXPECT_TRUE(absl::IsDataLoss(needs_gap.status())) << needs_gap.status();
  EXPECT_NE(needs_gap.status().message().find("missing"), std::string::npos) << needs_gap.status();
  // Reopened, the log continues above the floor; a floor already passed changes nothing.
  options.min_next_lsn = 5;
  auto wal = WalWriter::Open(dir.path(), options);
  ASSERT_TRUE(wal.ok());
  EXPECT_EQ((*wal)->Append(Payload(32)), 32u);
  // A log removed altogether starts at the floor too.
  fremen::testing::TempDir empty;
  options.min_next_lsn = 100;
  auto fresh = WalWriter::Open(empty.path(), options);
  ASSERT_TRUE(fresh.ok());
  EXPECT_EQ((*fresh)->Append(Payload(100)), 100u);
}

}  // namespace
}  // namespace fremen::storage
