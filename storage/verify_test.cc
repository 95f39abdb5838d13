#include "storage/verify.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/map_store.h"
#include "storage/shard_records.h"
#include "storage/store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

namespace fs = std::filesystem;
using testing::GridMap;
using testing::SweepScan;
using fremen::testing::TempDir;

std::string Describe(const VerifyReport& report) {
  std::string out;
  for (const VerifyProblem& p : report.problems) absl::StrAppend(&out, FormatProblem(p), "\n");
  for (const std::string& n : report.notes) absl::StrAppend(&out, "note: ", n, "\n");
  return out;
}

// Writes `batches` scans into a map at `dir` and closes it (which checkpoints).
void WriteMap(const MapInfo& info, const std::string& dir, uint64_t batches, size_t cells = 200,
              StoreOptions options = {}) {
  auto map = MapStore::Open(info, dir, options);
  ASSERT_TRUE(map.ok()) << map.status();
  for (uint64_t i = 0; i < batches; ++i) ASSERT_TRUE((*map)->Write(SweepScan(info, 1, i, cells)).ok());
  ASSERT_TRUE((*map)->Close().ok());
}

std::vector<uint8_t> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void WriteAt(const std::string& path, uint64_t offset, const std::vector<uint8_t>& bytes) {
  const int fd = open(path.c_str(), O_WRONLY);
  ASSERT_GE(fd, 0) << path;
  ASSERT_EQ(pwrite(fd, bytes.data(), bytes.size(), static_cast<off_t>(offset)), static_cast<ssize_t>(bytes.size()));
  close(fd);
}

// The byte offsets of the records of a log segment, read by the format documented in wal.h
// (u32 payload length | u32 CRC | u64 LSN | payload).
std::vector<uint64_t> RecordOffsets(const std::string& path) {
  const std::vector<uint8_t> data = ReadAll(path);
  std::vector<uint64_t> offsets;
  for (uint64_t pos = 0; pos + 16 <= data.size();) {
    offsets.push_back(pos);
    const uint32_t length = data[pos] | data[pos + 1] << 8 | data[pos + 2] << 16 | uint32_t{data[pos + 3]} << 24;
    pos += 16 + length;
  }
  return offsets;
}

std::vector<fs::path> Segments(const std::string& map_dir) {
  std::vector<fs::path> segments;
  for (const auto& e : fs::directory_iterator(map_dir + "/wal")) segments.push_back(e.path());
  std::sort(segments.begin(), segments.end());
  return segments;
}

TEST(VerifyTest, AHealthyMapVerifiesClean) {
  TempDir dir;
  const MapInfo info = GridMap("healthy", 64, 64, 1, 2);
  WriteMap(info, dir.path(), 40);
  for (const bool isolate : {false, true}) {
    VerifyOptions options;
    options.isolate = isolate;
    const VerifyReport report = VerifyMap(dir.path(), info, options);
    EXPECT_TRUE(report.clean()) << Describe(report);
    EXPECT_EQ(report.map, "healthy");
    ASSERT_EQ(report.shards.size(), 2u);
    for (const ShardVerifyReport& shard : report.shards) {
      EXPECT_TRUE(shard.read);
      EXPECT_GT(shard.records, 10u);
      EXPECT_GT(shard.record_bytes, 1000u);
      EXPECT_GT(shard.file_bytes, shard.record_bytes);
      ASSERT_TRUE(shard.checkpoint_lsn.has_value());
      EXPECT_EQ(*shard.checkpoint_lsn, 40u);  // Close checkpointed every batch
    }
    EXPECT_EQ(report.log.last_lsn, 40u);
    EXPECT_EQ(report.log.first_lsn, 1u);
    EXPECT_EQ(report.log.records, 40u);
    EXPECT_EQ(report.log.torn_tail_bytes, 0u);
  }
}

TEST(VerifyTest, VerifyingNeverChangesTheFiles) {
  TempDir dir;
  const MapInfo info = GridMap("untouched", 32, 32, 1, 1);
  WriteMap(info, dir.path(), 10);
  fs::remove(dir.path() + "/shard-0/lock.mdb");
  const auto before = ReadAll(dir.path() + "/shard-0/data.mdb");
  const auto segment = Segments(dir.path()).front();
  const auto log_before = ReadAll(segment);
  for (const bool isolate : {false, true}) {
    VerifyOptions options;
    options.isolate = isolate;
    EXPECT_TRUE(VerifyMap(dir.path(), info, options).clean());
  }
  EXPECT_EQ(ReadAll(dir.path() + "/shard-0/data.mdb"), before);
  EXPECT_EQ(ReadAll(segment), log_before);
  EXPECT_FALSE(fs::exists(dir.path() + "/shard-0/lock.mdb"));  // at rest: no lock file made
}

TEST(VerifyTest, AFlippedByteInTheNewestLogSegmentIsReportedWithSegmentAndOffset) {
  TempDir dir;
  const MapInfo info = GridMap("flip", 32, 32, 1, 1);
  WriteMap(info, dir.path(), 12);
  const fs::path segment = Segments(dir.path()).back();
  const std::vector<uint64_t> offsets = RecordOffsets(segment);
  ASSERT_GE(offsets.size(), 8u);
  const uint64_t damaged = offsets[5];
  auto byte = ReadAll(segment)[damaged + 40];
  WriteAt(segment, damaged + 40, {static_cast<uint8_t>(byte ^ 0x10)});

  const VerifyReport report = VerifyMap(dir.path(), info, {});
  ASSERT_FALSE(report.clean()) << Describe(report);
  bool named = false;
  for (const VerifyProblem& p : report.problems) {
    named |=
        p.file == "wal/" + segment.filename().string() && absl::StrContains(p.where, absl::StrCat("byte ", damaged));
  }
  EXPECT_TRUE(named) << Describe(report);
  EXPECT_EQ(report.log.last_lsn, 12u - offsets.size() + 5);
}

TEST(VerifyTest, AFlippedByteInAnOlderLogSegmentIsReportedWithSegmentAndOffset) {
  TempDir dir, image;
  const MapInfo info = GridMap("older", 32, 32, 1, 1);
  StoreOptions options;
  options.log_segment_bytes = 8 << 10;  // several segments
  {
    auto map = MapStore::Open(info, dir.path(), options);
    ASSERT_TRUE(map.ok()) << map.status();
    for (uint64_t i = 0; i < 30; ++i) ASSERT_TRUE((*map)->Write(SweepScan(info, 1, i, 200)).ok());
    // What a crash leaves: every acknowledged record is synced; no checkpoint has dropped the log.
    fs::copy(dir.path(), image.path(), fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  }
  const auto segments = Segments(image.path());
  ASSERT_GE(segments.size(), 3u);
  const fs::path segment = segments[1];
  const std::vector<uint64_t> offsets = RecordOffsets(segment);
  ASSERT_GE(offsets.size(), 2u);
  const uint64_t damaged = offsets[1];
  auto byte = ReadAll(segment)[damaged + 30];
  WriteAt(segment, damaged + 30, {static_cast<uint8_t>(byte ^ 0x01)});

  const VerifyReport report = VerifyMap(image.path(), info, {});
  ASSERT_FALSE(report.clean()) << Describe(report);
  bool named = false;
  for (const VerifyProblem& p : report.problems) {
    named |=
        p.file == "wal/" + segment.filename().string() && absl::StrContains(p.where, absl::StrCat("byte ", damaged));
  }
  EXPECT_TRUE(named) << Describe(report);
}

TEST(VerifyTest, AShardRecordThatFailsToDecodeIsReportedWithItsKey) {
  TempDir dir;
  const MapInfo info = GridMap("garbled", 32, 32, 1, 1);
  WriteMap(info, dir.path(), 10);
  const uint64_t key = info.grid.keys().Key(7, 3, 0);
  {
    LmdbOptions options;
    options.databases = shard_records::AllDatabases();
    auto env = LmdbEnv::Open(dir.path() + "/shard-0", options);
    ASSERT_TRUE(env.ok()) << env.status();
    ASSERT_TRUE((*env)
                    ->Write([&](LmdbTxn& txn) -> absl::Status {
                      auto db = txn.Db(shard_records::kDynamicDb);
                      if (!db.ok()) return db.status();
                      const std::string garbage = "\x06\x01 not a state model";
                      const auto k = KeyBytes(key);
                      return txn.Put(*db, k, {reinterpret_cast<const uint8_t*>(garbage.data()), garbage.size()});
                    })
                    .ok());
  }
  const VerifyReport report = VerifyMap(dir.path(), info, {});
  ASSERT_FALSE(report.clean());
  ASSERT_EQ(report.problems.size(), 1u) << Describe(report);
  EXPECT_EQ(report.problems[0].file, "shard-0/data.mdb");
  EXPECT_EQ(report.problems[0].where, absl::StrCat("dynamic record of key ", key));
  EXPECT_TRUE(report.shards[0].read);  // the scan went on past it
}

TEST(VerifyTest, ACheckpointPastTheLogIsReported) {
  TempDir dir;
  const MapInfo info = GridMap("gap", 32, 32, 1, 1);
  WriteMap(info, dir.path(), 5);
  fs::remove_all(dir.path() + "/wal");
  const VerifyReport report = VerifyMap(dir.path(), info, {});
  ASSERT_FALSE(report.clean());
  EXPECT_TRUE(absl::StrContains(Describe(report), "would reuse LSNs")) << Describe(report);
}

TEST(VerifyTest, AZeroedPageOfAShardIsReportedInIsolateModeAndTheCallerSurvives) {
  TempDir dir;
  const MapInfo info = GridMap("zeroed", 64, 64, 1, 1);
  WriteMap(info, dir.path(), 60, 800);
  const std::string file = dir.path() + "/shard-0/data.mdb";
  const uint64_t pages = fs::file_size(file) / 4096;
  ASSERT_GT(pages, 20u);
  const uint64_t page = pages / 2;
  WriteAt(file, page * 4096, std::vector<uint8_t>(4096, 0));
  VerifyOptions options;
  options.isolate = true;
  const VerifyReport report = VerifyMap(dir.path(), info, options);
  // LMDB asserts on this page (mdb_cursor_next: IS_LEAF): the child dies, the report says so.
  ASSERT_EQ(report.problems.size(), 1u) << Describe(report);
  EXPECT_EQ(FormatProblem(report.problems[0]), "shard-0/data.mdb: LMDB aborted reading it (signal 6)");
  EXPECT_FALSE(report.shards[0].read);
}

TEST(VerifyTest, GarbageAfterTheMetaPagesIsAProblemNamingTheFile) {
  TempDir dir;
  const MapInfo info = GridMap("aborted", 64, 64, 1, 1);
  WriteMap(info, dir.path(), 30, 400);
  const std::string file = dir.path() + "/shard-0/data.mdb";
  const uint64_t size = fs::file_size(file);
  std::vector<uint8_t> noise(size - 2 * 4096);
  for (size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<uint8_t>(i * 2654435761u >> 13);
  WriteAt(file, 2 * 4096, noise);
  VerifyOptions options;
  options.isolate = true;
  const VerifyReport report = VerifyMap(dir.path(), info, options);
  ASSERT_FALSE(report.clean());
  bool named = false;
  for (const VerifyProblem& p : report.problems) named |= p.file == "shard-0/data.mdb";
  EXPECT_TRUE(named) << Describe(report);
}

TEST(VerifyTest, AnOpenMapVerifiesCleanWhileItServes) {
  TempDir dir;
  const MapInfo info = GridMap("live", 32, 32, 1, 2);
  auto map = MapStore::Open(info, dir.path(), {});
  ASSERT_TRUE(map.ok()) << map.status();
  for (uint64_t i = 0; i < 10; ++i) ASSERT_TRUE((*map)->Write(SweepScan(info, 1, i, 100)).ok());
  ASSERT_TRUE((*map)->Checkpoint().ok());
  for (uint64_t i = 10; i < 20; ++i) ASSERT_TRUE((*map)->Write(SweepScan(info, 1, i, 100)).ok());
  const VerifyReport report = (*map)->Verify();
  EXPECT_TRUE(report.clean()) << Describe(report);
  EXPECT_EQ(report.log.last_lsn, 20u);
  ASSERT_EQ(report.shards.size(), 2u);
  EXPECT_EQ(report.shards[0].checkpoint_lsn, 10u);
  // The map still takes writes after it.
  EXPECT_TRUE((*map)->Write(SweepScan(info, 1, 20, 100)).ok());
}

// A store in `dir` with grid map "source" (2 shards) holding `batches` scans, backed up to
// `backup`/copy.
struct BackedUpMap {
  std::unique_ptr<Store> store;
  MapInfo info;
  std::string copy;
};

BackedUpMap BackUpAMap(const TempDir& dir, const TempDir& backup, uint64_t batches) {
  BackedUpMap b;
  auto store = Store::Open(dir.path(), {});
  EXPECT_TRUE(store.ok()) << store.status();
  b.store = *std::move(store);
  auto info = b.store->CreateMap(GridMap("source", 64, 64, 1, 2));
  EXPECT_TRUE(info.ok()) << info.status();
  b.info = *info;
  auto map = b.store->Map("source");
  EXPECT_TRUE(map.ok());
  for (uint64_t i = 0; i < batches; ++i) EXPECT_TRUE((*map)->Write(SweepScan(b.info, 1, i, 800)).ok());
  b.copy = backup.path() + "/copy";
  EXPECT_TRUE(b.store->BackupMap("source", b.copy).ok());
  return b;
}

TEST(VerifyTest, ARestoreOfADamagedBackupIsRefusedAndCreatesNothing) {
  TempDir dir, backup;
  BackedUpMap b = BackUpAMap(dir, backup, 40);
  ASSERT_FALSE(HasFailure());
  auto& store = b.store;
  const std::string& copy = b.copy;
  EXPECT_TRUE(VerifyShards(copy, b.info, {}).clean());
  ASSERT_TRUE(store->RestoreMap(copy, "intact").ok());  // a sound backup restores

  const std::string file = copy + "/shard-1/data.mdb";
  WriteAt(file, (fs::file_size(file) / 4096 / 2) * 4096, std::vector<uint8_t>(4096, 0));
  const auto maps_before = std::distance(fs::directory_iterator(dir.path() + "/maps"), fs::directory_iterator());
  const auto restored = store->RestoreMap(copy, "restored");
  ASSERT_TRUE(absl::IsDataLoss(restored.status())) << restored.status();
  EXPECT_TRUE(absl::StrContains(restored.status().message(), "shard-1/data.mdb")) << restored.status();
  EXPECT_TRUE(absl::IsNotFound(store->GetMap("restored").status()));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path() + "/maps"), fs::directory_iterator()), maps_before);
}

TEST(VerifyTest, ARestoreOrCheckPastItsDeadlineIsDeadlineExceededAndCreatesNothing) {
  TempDir dir, backup;
  BackedUpMap b = BackUpAMap(dir, backup, 10);
  ASSERT_FALSE(HasFailure());
  auto& store = b.store;
  const std::string& copy = b.copy;
  auto map = store->Map("source");
  ASSERT_TRUE(map.ok());

  // A deadline that has passed: no shard is read, and the check says so rather than "damaged".
  const VerifyReport late = (*map)->Verify(absl::InfinitePast());
  EXPECT_TRUE(late.deadline_exceeded);
  ASSERT_EQ(late.problems.size(), 1u) << Describe(late);
  EXPECT_EQ(late.problems[0].file, "shard-0/data.mdb");
  EXPECT_TRUE(absl::StrContains(late.problems[0].what, "not verified: the deadline had passed")) << Describe(late);
  EXPECT_EQ(late.shards.size(), 1u);  // the shards after it are not tried
  EXPECT_FALSE((*map)->Verify().deadline_exceeded);

  const auto maps_before = std::distance(fs::directory_iterator(dir.path() + "/maps"), fs::directory_iterator());
  const auto restored = store->RestoreMap(copy, "late", absl::InfinitePast());
  ASSERT_TRUE(absl::IsDeadlineExceeded(restored.status())) << restored.status();
  EXPECT_TRUE(absl::StrContains(restored.status().message(), "was not restored: its check did not finish"))
      << restored.status();
  EXPECT_TRUE(absl::IsNotFound(store->GetMap("late").status()));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path() + "/maps"), fs::directory_iterator()), maps_before);
  EXPECT_TRUE(store->RestoreMap(copy, "in-time").ok());
}

TEST(VerifyTest, AnOpenMapVerifiesCleanWhileBatchesAndCheckpointsGoOn) {
  TempDir dir;
  const MapInfo info = GridMap("busy", 64, 64, 1, 2);
  StoreOptions options;
  options.checkpoint_log_bytes = 64 << 10;  // checkpoints (and dropped segments) all along
  options.log_segment_bytes = 16 << 10;
  auto map = MapStore::Open(info, dir.path(), options);
  ASSERT_TRUE(map.ok()) << map.status();
  for (uint64_t i = 0; i < 20; ++i) ASSERT_TRUE((*map)->Write(SweepScan(info, 1, i, 200)).ok());
  std::atomic<bool> stop = false;
  std::atomic<uint64_t> written = 0, failed = 0;
  std::thread writer([&] {
    for (uint64_t i = 20; !stop.load(); ++i) {
      if ((*map)->Write(SweepScan(info, 1, i, 200)).ok()) {
        written.fetch_add(1);
      } else {
        failed.fetch_add(1);
      }
    }
  });
  std::vector<VerifyReport> reports;
  for (int round = 0; round < 5; ++round) reports.push_back((*map)->Verify());
  stop = true;
  writer.join();
  EXPECT_EQ(failed.load(), 0u);
  for (const VerifyReport& report : reports) {
    EXPECT_TRUE(report.clean()) << Describe(report);
    EXPECT_GE(report.log.last_lsn, 20u);
  }
}

TEST(VerifyTest, ADataDirectoryIsVerifiedMapByMapWithItsCatalog) {
  TempDir dir;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok()) << store.status();
    for (const char* name : {"a", "b"}) {
      auto info = (*store)->CreateMap(GridMap(name, 32, 32, 1, 1));
      ASSERT_TRUE(info.ok()) << info.status();
      auto map = (*store)->Map(name);
      ASSERT_TRUE(map.ok());
      for (uint64_t i = 0; i < 5; ++i) ASSERT_TRUE((*map)->Write(SweepScan(*info, 1, i, 100)).ok());
    }
  }
  DataDirVerifyReport report = VerifyDataDir(dir.path(), {});
  EXPECT_TRUE(report.clean());
  ASSERT_EQ(report.maps.size(), 2u);
  EXPECT_EQ(report.maps[0].map, "a");
  EXPECT_EQ(report.maps[1].map, "b");
  EXPECT_EQ(report.maps[1].log.last_lsn, 5u);

  // A directory the catalog does not name is reported (a store opening the directory would remove it).
  fs::create_directories(dir.path() + "/maps/999/shard-0");
  report = VerifyDataDir(dir.path(), {});
  EXPECT_FALSE(report.clean());
  ASSERT_EQ(report.problems.size(), 1u);
  EXPECT_EQ(report.problems[0].file, "maps/999");
  EXPECT_EQ(report.maps.size(), 2u);
  EXPECT_TRUE(fs::exists(dir.path() + "/maps/999"));
}

}  // namespace
}  // namespace fremen::storage
