#include "storage/wal/wal.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "storage/testing/temp_dir.h"

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

TEST(WalTest, ReplaysWhatWasSyncedInOrderAfterAGivenLsn) {
  testing::TempDir dir;
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
  testing::TempDir dir;
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
  testing::TempDir dir;
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
  auto wal = WalWriter::Open(dir.path(), {});
  ASSERT_TRUE(wal.ok()) << wal.status();
  EXPECT_EQ((*wal)->Append(Payload(20)), 20u);
  ASSERT_TRUE((*wal)->Sync().ok());
  EXPECT_EQ(ReplayAll(dir.path(), 0, &result).size(), 20u);
  EXPECT_FALSE(result.truncated_tail);
}

TEST(WalTest, SegmentsRollAndCheckpointedOnesAreDropped) {
  testing::TempDir dir;
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
  testing::TempDir dir;
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

}  // namespace
}  // namespace fremen::storage
