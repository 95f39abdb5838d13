// A map's recovery from a damaged write-ahead log (storage/README.md, "Torn tail and corruption"):
// the two losses it once caused — a corrupt record taken for a torn tail and cut, and records
// written below the checkpoint's LSN and then skipped — each pinned by a test of the whole store.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <mutex>

#include "storage/map_store.h"
#include "storage/testing/crash_image.h"
#include "storage/testing/file_damage.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

constexpr size_t kCells = 50;

std::string OnlySegment(const std::string& map_dir) {
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(map_dir + "/wal")) segments.push_back(e.path());
  EXPECT_EQ(segments.size(), 1u);
  return segments.empty() ? "" : segments.front();
}

using testing::OverwriteBytes;
using testing::ReadWholeFile;

StoreOptions NoCheckpointsUntilClose() {
  StoreOptions options;
  options.checkpoint_log_bytes = 1ull << 40;
  return options;
}

// Before: replay took the flip for a torn tail, cut the log there and served the map without the 20
// acknowledged batches after it.
TEST(WalRecoveryTest, ACorruptRecordAfterAcknowledgedBatchesFailsTheMapAndCutsNothing) {
  fremen::testing::TempDir dir, image;
  const MapInfo map = testing::GridMap("m", 32, 32, 1, 2);
  {
    auto store = MapStore::Open(map, dir.path(), NoCheckpointsUntilClose());
    ASSERT_TRUE(store.ok()) << store.status();
    for (uint64_t i = 0; i < 40; ++i) ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, i, kCells)).ok());
    testing::CopyCrashImage(dir.path(), image.path());  // killed here: only the log has the batches
  }
  const std::string segment = OnlySegment(image.path());
  const uint64_t size = std::filesystem::file_size(segment);
  OverwriteBytes(segment, size / 2, std::string(16, '\xa5'));
  const std::string damaged = ReadWholeFile(segment);
  auto reopened = MapStore::Open(map, image.path(), {});
  ASSERT_FALSE(reopened.ok());
  EXPECT_TRUE(absl::IsDataLoss(reopened.status())) << reopened.status();
  const std::string message(reopened.status().message());
  EXPECT_NE(message.find(segment), std::string::npos) << message;
  EXPECT_NE(message.find("byte "), std::string::npos) << message;
  EXPECT_NE(message.find("LSN "), std::string::npos) << message;
  EXPECT_EQ(ReadWholeFile(segment), damaged) << "nothing may be cut";
  EXPECT_EQ(OnlySegment(image.path()), segment);
}

// Before: the writer resumed at the cut record's LSN, at or below the shards' checkpoint, and the
// next recovery skipped the new records as checkpointed (20 of 30 acknowledged batches gone).
TEST(WalRecoveryTest, RecordsWrittenAfterARecoveryNeverFallBelowTheCheckpoint) {
  fremen::testing::TempDir dir, image;
  const MapInfo map = testing::GridMap("m", 32, 32, 1, 2);
  {
    auto store = MapStore::Open(map, dir.path(), NoCheckpointsUntilClose());
    ASSERT_TRUE(store.ok());
    for (uint64_t i = 0; i < 30; ++i) ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, i, kCells)).ok());
  }  // closed: checkpointed at LSN 30, and the log keeps its segment
  // Bit rot in the last record, with nothing after it: judged a torn tail and cut, so that the log
  // now ends below the checkpoint.
  const std::string segment = OnlySegment(dir.path());
  OverwriteBytes(segment, std::filesystem::file_size(segment) - 2, "\x01\x02");
  std::mutex warnings_mutex;
  std::vector<std::string> warnings;
  StoreOptions options = NoCheckpointsUntilClose();
  options.log_warning = [&](const std::string& line) {
    std::lock_guard lock(warnings_mutex);
    warnings.push_back(line);
  };
  {
    auto store = MapStore::Open(map, dir.path(), options);
    ASSERT_TRUE(store.ok()) << store.status();
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("torn tail of "), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find(segment), std::string::npos) << warnings[0];
    EXPECT_EQ((*store)->Stats().totals.observations, 30 * kCells) << "the checkpoint holds all 30";
    for (uint64_t i = 30; i < 60; ++i) {
      auto ack = (*store)->Write(testing::SweepScan(map, 1, i, kCells));
      ASSERT_TRUE(ack.ok());
      EXPECT_GT(ack->lsn, 30u) << "at or below the checkpoint LSN";
    }
    testing::CopyCrashImage(dir.path(),
                            image.path());  // killed: the 30 new batches are only in the log
  }
  auto recovered = MapStore::Open(map, image.path(), {});
  ASSERT_TRUE(recovered.ok()) << recovered.status();
  EXPECT_EQ((*recovered)->Stats().totals.observations, 60 * kCells);
}

TEST(WalRecoveryTest, ALogRemovedAltogetherRestartsAboveTheCheckpoint) {
  fremen::testing::TempDir dir, image;
  const MapInfo map = testing::GridMap("m", 32, 32, 1, 2);
  {
    auto store = MapStore::Open(map, dir.path(), NoCheckpointsUntilClose());
    ASSERT_TRUE(store.ok());
    for (uint64_t i = 0; i < 10; ++i) ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, i, kCells)).ok());
  }
  std::filesystem::remove_all(dir.path() + "/wal");
  {
    auto store = MapStore::Open(map, dir.path(), NoCheckpointsUntilClose());
    ASSERT_TRUE(store.ok()) << store.status();
    for (uint64_t i = 10; i < 20; ++i) ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, i, kCells)).ok());
    testing::CopyCrashImage(dir.path(), image.path());
  }
  auto recovered = MapStore::Open(map, image.path(), {});
  ASSERT_TRUE(recovered.ok()) << recovered.status();
  EXPECT_EQ((*recovered)->Stats().totals.observations, 20 * kCells);
}

}  // namespace
}  // namespace fremen::storage
