// The store under damaged files (docs/storage.md, "When the disk misbehaves"): a flipped bit in a record is DataLoss
// naming the file and key, never another model; a damaged catalog record deletes nothing; a map whose file would make
// LMDB abort fails alone while the others serve.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/escaping.h"
#include "storage/catalog.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/lmdb/record_checksum.h"
#include "storage/model/record_codec.h"
#include "storage/store.h"
#include "storage/testing/file_damage.h"
#include "storage/testing/labelled_states.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::Bytes;
using testing::Fill;
using testing::Fingerprints;
using testing::Generic;
using testing::kStates;
using testing::Record;
using testing::ShardRecords;
using fremen::testing::TempDir;

// Before record checksums, 3 of 1,024 models came back with a different spectrum and no error after single-bit flips in
// shard records. Now every flip of a bit of a record (value or checksum) is found: the map fails with DataLoss naming
// its file and the record's key; no model is served from damaged bytes.
TEST(StoreIntegrityTest, SingleBitFlipsInShardRecordsAreDataLossNeverAnotherModel) {
  TempDir dir;
  uint64_t id = 0;
  std::map<uint64_t, std::string> want;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok()) << store.status();
    auto info = (*store)->CreateMap(Generic("m"));
    ASSERT_TRUE(info.ok()) << info.status();
    id = info->id;
    auto map = *(*store)->Map("m");
    Fill(*map);
    want = Fingerprints(*map);
  }
  ASSERT_EQ(want.size(), kStates);
  const std::string shard_dir = MapDirIn(dir.path(), id) + "/shard-0", file = shard_dir + "/data.mdb";
  {
    // Undamaged, the map comes back whole.
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok());
    auto map = (*store)->Map("m");
    ASSERT_TRUE(map.ok()) << map.status();
    ASSERT_EQ(Fingerprints(**map), want);
  }
  const std::string pristine = testing::ReadWholeFile(file);
  // Where each record's value and checksum lie in the file (found by their bytes: the live copy and any stale ones LMDB
  // left on free pages).
  struct Target {
    std::vector<size_t> offsets;
    size_t size;
    std::string hex_key;
  };
  std::vector<Target> targets;
  size_t dynamic_targets = 0;
  for (const Record& r : ShardRecords(shard_dir)) {
    if (r.value.size() < 16) continue;  // short values (an 8-byte LSN) may occur by chance elsewhere
    std::vector<size_t> offsets = testing::FindAll(pristine, Bytes(r.value));
    ASSERT_FALSE(offsets.empty()) << r.db << " record " << absl::BytesToHexString(r.key) << " not found";
    targets.push_back({std::move(offsets), r.value.size() + kRecordChecksumBytes, absl::BytesToHexString(r.key)});
    dynamic_targets += r.db == "dynamic";
  }
  ASSERT_EQ(dynamic_targets, kStates - kStates / 4);

  std::mt19937_64 rng(11);
  constexpr int kFlips = 64;  // each costs a store open (~0.15 s); LmdbEnvTest
                              // flips every bit of a record
  int data_loss = 0;
  for (int flip = 0; flip < kFlips; ++flip) {
    const Target& target = targets[rng() % targets.size()];
    const size_t delta = rng() % target.size;
    const int bit = static_cast<int>(rng() % 8);
    testing::WriteWholeFile(file, pristine);
    for (const size_t at : target.offsets) testing::FlipBit(file, at + delta, bit);
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok()) << store.status();  // the daemon would go on serving its other maps
    auto map = (*store)->Map("m");
    if (map.ok()) {
      ASSERT_EQ(Fingerprints(**map), want)
          << "key " << target.hex_key << " byte " << delta << " bit " << bit << ": a different model, no error";
      continue;
    }
    ASSERT_TRUE(absl::IsDataLoss(map.status())) << map.status();
    EXPECT_NE(map.status().message().find(file), std::string::npos) << map.status();
    EXPECT_NE(map.status().message().find("key " + target.hex_key), std::string::npos)
        << target.hex_key << " " << map.status();
    ASSERT_EQ((*store)->FailedMaps().size(), 1u);
    EXPECT_EQ((*store)->FailedMaps()[0].status, map.status());
    ++data_loss;
  }
  // A CRC catches every single-bit error: not one flip went unnoticed.
  EXPECT_EQ(data_loss, kFlips);
  // The damaged file is left as it was found, for an operator (and the verifier) to see.
  EXPECT_NE(testing::ReadWholeFile(file), pristine);
}

// Before: one flipped bit in the catalog changed a map's id, and the next start removed the map's directory as
// unknown. Now the record is DataLoss, the map is failed, and nothing is removed.
TEST(StoreIntegrityTest, ACatalogBitFlipDeletesNothingAndIsReported) {
  TempDir dir;
  MapInfo alpha;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok());
    auto created = (*store)->CreateMap(Generic("alpha"));
    ASSERT_TRUE(created.ok());
    alpha = *created;
    ASSERT_TRUE((*store)->CreateMap(Generic("beta")).ok());
    Fill(**(*store)->Map("alpha"));
    Fill(**(*store)->Map("beta"));
  }
  const std::string catalog = dir.path() + "/catalog/data.mdb";
  const std::string encoded = EncodeMapInfo(alpha);
  const std::vector<size_t> copies = testing::FindAll(testing::ReadWholeFile(catalog), Bytes(encoded));
  ASSERT_FALSE(copies.empty());
  // version | name length | "alpha" | id: the id's lowest bit (the flip that used to change a map's id).
  for (const size_t at : copies) testing::FlipBit(catalog, at + 2 + alpha.name.size(), 0);
  const std::string alpha_dir = MapDirIn(dir.path(), alpha.id);
  const std::string shard_file = alpha_dir + "/shard-0/data.mdb";
  const std::string before = testing::ReadWholeFile(shard_file);

  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  // The other map serves.
  auto beta = (*store)->Map("beta");
  ASSERT_TRUE(beta.ok()) << beta.status();
  EXPECT_EQ(Fingerprints(**beta).size(), kStates);
  // alpha is failed, named by its key, with the catalog file named.
  auto failed = (*store)->Map("alpha");
  ASSERT_TRUE(absl::IsDataLoss(failed.status())) << failed.status();
  EXPECT_NE(failed.status().message().find(catalog), std::string::npos) << failed.status();
  EXPECT_NE(failed.status().message().find("key " + absl::BytesToHexString("alpha")), std::string::npos)
      << failed.status();
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  EXPECT_EQ((*store)->FailedMaps()[0].name, "alpha");
  EXPECT_TRUE(absl::IsDataLoss((*store)->GetMap("alpha").status()));
  auto page = (*store)->ListMaps(0, "");
  ASSERT_TRUE(page.ok()) << page.status();
  ASSERT_EQ(page->maps.size(), 1u);
  EXPECT_EQ(page->maps[0].name, "beta");
  ASSERT_EQ(page->damaged.size(), 1u);
  EXPECT_EQ(page->damaged[0].key, "alpha");
  // Nothing deleted: the directory and its data are there, reported for an operator.
  EXPECT_EQ((*store)->UnknownDirectories(), std::vector<std::string>{alpha_dir});
  EXPECT_EQ(testing::ReadWholeFile(shard_file), before);
  // And no new map is given the directory's id.
  auto gamma = (*store)->CreateMap(Generic("gamma"));
  ASSERT_TRUE(gamma.ok()) << gamma.status();
  EXPECT_NE(gamma->id, alpha.id);
  EXPECT_EQ(testing::ReadWholeFile(shard_file), before);
}

// Before the probe: a zeroed page in a shard's data.mdb aborted the daemon at start, naming nothing. Now the probe
// finds it: Store::Open succeeds, the map is failed naming the file, the others serve.
TEST(StoreIntegrityTest, AZeroedShardPageFailsThatMapAloneNamingTheFile) {
  TempDir dir;
  uint64_t bad_id = 0;
  std::map<uint64_t, std::string> good_models;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok());
    ASSERT_TRUE((*store)->CreateMap(Generic("good")).ok());
    bad_id = (*store)->CreateMap(Generic("bad"))->id;
    Fill(**(*store)->Map("good"));
    Fill(**(*store)->Map("bad"));
    good_models = Fingerprints(**(*store)->Map("good"));
  }
  const std::string shard_dir = MapDirIn(dir.path(), bad_id) + "/shard-0", file = shard_dir + "/data.mdb";
  // Zero a leaf page holding dynamic records, in the middle of the file.
  std::vector<Record> dynamic;
  for (Record& r : ShardRecords(shard_dir)) {
    if (r.db == "dynamic") dynamic.push_back(std::move(r));
  }
  ASSERT_FALSE(dynamic.empty());
  const std::vector<size_t> copies =
      testing::FindAll(testing::ReadWholeFile(file), Bytes(dynamic[dynamic.size() / 2].value));
  ASSERT_FALSE(copies.empty());
  for (const size_t at : copies) {
    ASSERT_GT(at / 4096, 1u);  // never a meta page
    testing::ZeroPage(file, at / 4096);
  }

  // Without the probe, this file kills the process that opens the store (here a death test's child).
  StoreOptions unguarded;
  unguarded.probe_before_open = false;
  EXPECT_DEATH((void)Store::Open(dir.path(), unguarded), "Assertion");

  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  auto good = (*store)->Map("good");
  ASSERT_TRUE(good.ok()) << good.status();
  EXPECT_EQ(Fingerprints(**good), good_models);
  auto bad = (*store)->Map("bad");
  ASSERT_TRUE(absl::IsDataLoss(bad.status())) << bad.status();
  EXPECT_NE(bad.status().message().find(file + " is damaged: LMDB aborted reading it (signal 6"), std::string::npos)
      << bad.status();
  const std::vector<FailedMap> failed = (*store)->FailedMaps();
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_EQ(failed[0].name, "bad");
  EXPECT_EQ(failed[0].id, bad_id);
  EXPECT_EQ(failed[0].dir, MapDirIn(dir.path(), bad_id));
  // Still in the catalog: listed, with its info.
  EXPECT_TRUE((*store)->GetMap("bad").ok());
  EXPECT_TRUE((*store)->UnknownDirectories().empty());
  EXPECT_TRUE(std::filesystem::exists(file));
  // Writes to the good map go on.
  ObservationBatch b;
  b.writer_id = 2;
  b.sequence = 1;
  b.time = 1.8e9;
  b.keys = {1};
  b.values = {1.0f};
  EXPECT_TRUE((*good)->Write(b).ok());
  // An operator may delete the failed map deliberately: then, and only then, its files go.
  ASSERT_TRUE((*store)->DeleteMap("bad").ok());
  EXPECT_FALSE(std::filesystem::exists(MapDirIn(dir.path(), bad_id)));
  EXPECT_TRUE((*store)->FailedMaps().empty());
  EXPECT_TRUE(absl::IsNotFound((*store)->Map("bad").status()));
}

// A damaged backup is refused by RestoreMap (the copy is probed and loaded before the map is listed), with the file
// named; what the call copied is removed, nothing else.
TEST(StoreIntegrityTest, RestoringADamagedBackupFailsNamingTheFileAndLeavesNothing) {
  TempDir dir, backup;
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_TRUE((*store)->CreateMap(Generic("m")).ok());
  Fill(**(*store)->Map("m"));
  ASSERT_TRUE((*store)->BackupMap("m", backup.path() + "/copy").ok());
  const std::string copy = backup.path() + "/copy/shard-0";
  std::vector<Record> dynamic;
  for (Record& r : ShardRecords(copy)) {
    if (r.db == "dynamic") dynamic.push_back(std::move(r));
  }
  ASSERT_FALSE(dynamic.empty());
  const std::string copy_file = copy + "/data.mdb";
  for (const size_t at :
       testing::FindAll(testing::ReadWholeFile(copy_file), Bytes(dynamic[dynamic.size() / 2].value))) {
    testing::ZeroPage(copy_file, at / 4096);
  }
  auto restored = (*store)->RestoreMap(backup.path() + "/copy", "restored");
  ASSERT_TRUE(absl::IsDataLoss(restored.status())) << restored.status();
  EXPECT_NE(restored.status().message().find("shard-0/data.mdb: LMDB aborted reading it"), std::string::npos)
      << restored.status();
  EXPECT_TRUE(absl::IsNotFound((*store)->GetMap("restored").status()));
  EXPECT_TRUE((*store)->FailedMaps().empty());
  size_t map_dirs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path() + "/maps")) map_dirs += entry.is_directory();
  EXPECT_EQ(map_dirs, 1u);                          // only "m"'s: the restore's copy is gone
  EXPECT_TRUE(std::filesystem::exists(copy_file));  // the backup itself is left as it was
  EXPECT_TRUE((*store)->Map("m").ok());
}

}  // namespace
}  // namespace fremen::storage
