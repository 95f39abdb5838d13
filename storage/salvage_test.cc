// Store::SalvageMap on maps damaged as a bad disk would damage them: a flipped bit in a shard record, a zeroed LMDB
// page that makes LMDB abort, a corrupt record in the middle of the log. What verifies is kept, exactly, what does not
// is reported, and the damaged map's files are left as they were.
#include "storage/salvage.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "storage/catalog.h"
#include "storage/cell_key.h"
#include "storage/env/fault_injection_env.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/shard_records.h"
#include "storage/static_bricks.h"
#include "storage/store.h"
#include "storage/testing/crash_image.h"
#include "storage/testing/file_damage.h"
#include "storage/testing/labelled_states.h"
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

const SalvageDatabase& Db(const SalvageReport& report, const std::string& name) {
  for (const SalvageDatabase& d : report.shards.at(0).databases) {
    if (d.name == name) return d;
  }
  static const SalvageDatabase none;
  ADD_FAILURE() << "no database " << name << " in the report";
  return none;
}

std::vector<Record> RecordsOf(const std::string& shard_dir, const std::string& db) {
  std::vector<Record> out;
  for (Record& r : ShardRecords(shard_dir)) {
    if (r.db == db) out.push_back(std::move(r));
  }
  return out;
}

// A store with map "m" filled and closed (so checkpointed); returns the map's info and every state's model.
MapInfo FilledMap(const TempDir& dir, std::map<uint64_t, std::string>& models) {
  auto store = Store::Open(dir.path(), {});
  EXPECT_TRUE(store.ok()) << store.status();
  auto info = (*store)->CreateMap(Generic("m"));
  EXPECT_TRUE(info.ok()) << info.status();
  auto map = *(*store)->Map("m");
  Fill(*map);
  models = Fingerprints(*map);
  return *info;
}

TEST(SalvageTest, OnlyAFailedMapIsSalvagedAndNamesAreChecked) {
  TempDir dir;
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_TRUE((*store)->CreateMap(Generic("m")).ok());
  ASSERT_TRUE((*store)->CreateMap(Generic("other")).ok());
  auto healthy = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(absl::IsFailedPrecondition(healthy.status())) << healthy.status();
  EXPECT_EQ(healthy.status().message(), "map m is not damaged; use BackupMap/RestoreMap to copy it");
  auto unknown = (*store)->SalvageMap("nope", "");
  EXPECT_TRUE(absl::IsNotFound(unknown.status())) << unknown.status();
  EXPECT_NE(unknown.status().message().find("nope"), std::string::npos);
  EXPECT_TRUE(absl::IsNotFound((*store)->GetMap("m-salvaged").status()));
}

TEST(SalvageTest, AFlippedBitLosesThatRecordAndKeepsEveryOther) {
  TempDir dir;
  std::map<uint64_t, std::string> want;
  const MapInfo info = FilledMap(dir, want);
  ASSERT_EQ(want.size(), kStates);
  const std::string shard_dir = MapDirIn(dir.path(), info.id) + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<Record> dynamic = RecordsOf(shard_dir, "dynamic");
  const size_t statics = RecordsOf(shard_dir, "static").size();
  ASSERT_EQ(dynamic.size(), kStates - kStates / 4);
  const Record& victim = dynamic[dynamic.size() / 3];
  const uint64_t victim_key = KeyFromBytes(reinterpret_cast<const uint8_t*>(victim.key.data()));
  for (const size_t at : testing::FindAll(testing::ReadWholeFile(file), Bytes(victim.value))) {
    testing::FlipBit(file, at + victim.value.size() / 2, 3);
  }
  const std::string damaged = testing::ReadWholeFile(file);

  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  // The name taken by another map is refused before anything is made.
  ASSERT_TRUE((*store)->CreateMap(Generic("taken")).ok());
  auto taken = (*store)->SalvageMap("m", "taken");
  ASSERT_TRUE(absl::IsAlreadyExists(taken.status())) << taken.status();
  EXPECT_NE(taken.status().message().find("new_map"), std::string::npos) << taken.status();

  auto report = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->from, "m");
  EXPECT_EQ(report->map.name, "m-salvaged");
  EXPECT_NE(report->map.id, info.id);
  EXPECT_EQ(report->map.kind, info.kind);
  EXPECT_EQ(report->map.shards, info.shards);
  ASSERT_EQ(report->shards.size(), 1u);
  EXPECT_EQ(Db(*report, "dynamic").kept, dynamic.size() - 1);
  EXPECT_EQ(Db(*report, "dynamic").lost, 1u);
  EXPECT_EQ(Db(*report, "static").kept, statics);
  EXPECT_EQ(Db(*report, "labels").kept, kStates);
  EXPECT_EQ(report->records_lost(), 1u);
  ASSERT_EQ(report->losses, 1u);
  ASSERT_EQ(report->lost.size(), 1u);
  EXPECT_EQ(report->lost[0].file, "shard-0/data.mdb");
  EXPECT_NE(report->lost[0].what.find("key " + absl::BytesToHexString(victim.key)), std::string::npos)
      << report->lost[0].what;

  // Served: every state as it was, but the one whose record was lost, which has no changed model.
  auto salvaged = (*store)->Map("m-salvaged");
  ASSERT_TRUE(salvaged.ok()) << salvaged.status();
  std::map<uint64_t, std::string> got = Fingerprints(**salvaged), expected = want;
  const auto lost_state = (*salvaged)->Snapshot(victim_key);
  EXPECT_FALSE(lost_state && !lost_state->is_static) << "a changed model served from a damaged record";
  got.erase(victim_key);
  expected.erase(victim_key);
  EXPECT_EQ(got, expected);
  const VerifyReport verified = (*salvaged)->Verify();
  EXPECT_TRUE(verified.clean()) << (verified.problems.empty() ? "" : FormatProblem(verified.problems[0]));
  // The damaged map is untouched and still failed.
  EXPECT_EQ(testing::ReadWholeFile(file), damaged);
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  EXPECT_EQ((*store)->FailedMaps()[0].name, "m");
  // A second salvage under the same name is refused: the first one's map is there.
  EXPECT_TRUE(absl::IsAlreadyExists((*store)->SalvageMap("m", "").status()));

  // The salvaged map is an ordinary map: it comes back at the next start.
  ASSERT_TRUE((*store)->Close().ok());
  store->reset();
  auto reopened = Store::Open(dir.path(), {});
  ASSERT_TRUE(reopened.ok());
  auto again = (*reopened)->Map("m-salvaged");
  ASSERT_TRUE(again.ok()) << again.status();
  got = Fingerprints(**again);
  got.erase(victim_key);
  EXPECT_EQ(got, expected);
}

TEST(SalvageTest, AnLmdbAbortKeepsTheRecordsReadBeforeItAndTheOtherDatabases) {
  TempDir dir;
  std::map<uint64_t, std::string> want;
  const MapInfo info = FilledMap(dir, want);
  const std::string shard_dir = MapDirIn(dir.path(), info.id) + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<Record> dynamic = RecordsOf(shard_dir, "dynamic");
  const size_t statics = RecordsOf(shard_dir, "static").size();
  for (const size_t at : testing::FindAll(testing::ReadWholeFile(file), Bytes(dynamic[dynamic.size() / 2].value))) {
    ASSERT_GT(at / 4096, 1u);  // never a meta page
    testing::ZeroPage(file, at / 4096);
  }
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);  // the probe found the page: LMDB would abort on it

  auto report = (*store)->SalvageMap("m", "rescued");
  ASSERT_TRUE(report.ok()) << report.status();
  const SalvageDatabase& d = Db(*report, "dynamic");
  // The scan died in the zeroed page: what came before it is kept, and LMDB's count says how much was not read.
  EXPECT_GT(d.kept, 0u);
  EXPECT_GT(d.lost, 0u);
  EXPECT_EQ(d.kept + d.lost, dynamic.size());
  EXPECT_EQ(Db(*report, "static").kept, statics);
  EXPECT_EQ(Db(*report, "labels").kept + Db(*report, "labels").lost, kStates);
  bool named = false;
  for (const VerifyProblem& p : report->lost) {
    named |= p.file == "shard-0/data.mdb" && p.what.find("LMDB aborted reading it (signal 6)") != std::string::npos;
  }
  EXPECT_TRUE(named) << "no loss names the abort";

  // Exactly the first d.kept changed states (key order, as LMDB scans) survive; the others have no changed model.
  auto map = (*store)->Map("rescued");
  ASSERT_TRUE(map.ok()) << map.status();
  const std::map<uint64_t, std::string> got = Fingerprints(**map);
  for (size_t i = 0; i < dynamic.size(); ++i) {
    const uint64_t key = KeyFromBytes(reinterpret_cast<const uint8_t*>(dynamic[i].key.data()));
    const auto snapshot = (*map)->Snapshot(key);
    if (i < d.kept) {
      ASSERT_TRUE(snapshot && !snapshot->is_static) << "state " << key;
      ASSERT_TRUE(got.contains(key));
      EXPECT_EQ(got.at(key), want[key]) << "state " << key;
    } else {
      EXPECT_FALSE(snapshot && !snapshot->is_static) << "state " << key << " was past the abort";
    }
  }
  // Never-changed states were in another database: all kept.
  for (uint64_t k = 4; k <= kStates; k += 4) {
    const auto snapshot = (*map)->Snapshot(k);
    ASSERT_TRUE(snapshot && snapshot->is_static) << "state " << k;
    ASSERT_TRUE(got.contains(k));
    EXPECT_EQ(got.at(k), want[k]) << "state " << k;
  }
}

// A state stored both as never changed and as changed (the verifier's "also stored as never changed") in a map failed
// by another damaged record: the changed model is kept, the never-changed copy dropped and reported.
TEST(SalvageTest, AStateStoredBothAsNeverChangedAndChangedKeepsItsChangedModel) {
  TempDir dir;
  std::map<uint64_t, std::string> want;
  const MapInfo info = FilledMap(dir, want);
  const std::string shard_dir = MapDirIn(dir.path(), info.id) + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<Record> dynamic = RecordsOf(shard_dir, "dynamic");
  const size_t statics = RecordsOf(shard_dir, "static").size();
  {
    // Brick 0 gains a never-changed copy of state 1 (a changed state: 1 % 4 != 0).
    LmdbOptions options;
    options.databases = shard_records::AllDatabases();
    auto env = LmdbEnv::Open(shard_dir, options);
    ASSERT_TRUE(env.ok()) << env.status();
    ASSERT_TRUE((*env)
                    ->Write([&](LmdbTxn& txn) -> absl::Status {
                      const auto key = KeyBytes(0);
                      auto stored = txn.Get(*txn.Db(shard_records::kStaticDb), key);
                      if (!stored.ok()) return stored.status();
                      auto brick = StaticBrick::Decode(
                          std::string_view(reinterpret_cast<const char*>(stored->data()), stored->size()));
                      if (!brick.ok()) return brick.status();
                      StaticBrick twisted;
                      bool added = false;
                      brick->ForEach([&](uint32_t i, const model::StaticState& state) {
                        if (!added && i > 1) {
                          twisted.Add(1, state);
                          added = true;
                        }
                        twisted.Add(i, state);
                      });
                      return txn.Put(*txn.Db(shard_records::kStaticDb), key, Bytes(twisted.Encode()));
                    })
                    .ok());
  }
  // And another state's record is damaged, so that the map fails to open.
  const Record& victim = dynamic[1];
  const uint64_t victim_key = KeyFromBytes(reinterpret_cast<const uint8_t*>(victim.key.data()));
  ASSERT_NE(victim_key, 1u);
  for (const size_t at : testing::FindAll(testing::ReadWholeFile(file), Bytes(victim.value))) {
    testing::FlipBit(file, at + 7, 2);
  }
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  auto report = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(Db(*report, "static").kept, statics);
  EXPECT_EQ(Db(*report, "dynamic").kept, dynamic.size() - 1);
  EXPECT_EQ(report->losses, 2u);
  bool named = false;
  for (const VerifyProblem& p : report->lost) {
    named |= p.where == "static record of key 0" &&
             p.what == "state 1 is also stored as changed: its never-changed copy was dropped";
  }
  EXPECT_TRUE(named);
  auto map = (*store)->Map("m-salvaged");
  ASSERT_TRUE(map.ok()) << map.status();
  std::map<uint64_t, std::string> got = Fingerprints(**map);
  got.erase(victim_key);
  want.erase(victim_key);
  EXPECT_EQ(got, want);  // state 1 too: its changed model
  // And the new map's files verify clean: the never-changed copy is gone from them.
  const VerifyReport verified = (*map)->Verify();
  EXPECT_TRUE(verified.clean()) << (verified.problems.empty() ? "" : FormatProblem(verified.problems[0]));
}

// A lossless map whose state lost its changed record: the state's lossless history goes with it (a history without its
// state would not load), reported; every other state keeps its model and its history.
TEST(SalvageTest, ALosslessHistoryWhoseStateWasLostIsDroppedAndReported) {
  TempDir dir;
  constexpr uint64_t kKeys = 16;
  MapInfo info = Generic("m");
  info.lossless_sampling_period = 60;
  info.lossless_origin = 1.7e9;
  std::map<uint64_t, StateSnapshot> want;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok());
    info = *(*store)->CreateMap(info);
    auto map = *(*store)->Map("m");
    for (uint64_t i = 0; i < 200; ++i) {
      ObservationBatch b;
      b.writer_id = 1;
      b.sequence = i + 1;
      b.time = 1.7e9 + 60.0 * i + 1;
      for (uint64_t k = 1; k <= kKeys; ++k) {
        b.keys.push_back(k);
        b.values.push_back((i / (k + 2)) % 2 == 0 || i % (k + 5) == 0 ? 1.0f : 0.0f);
      }
      ASSERT_TRUE(map->Write(b).ok());
    }
    for (uint64_t k = 1; k <= kKeys; ++k) want[k] = *map->Snapshot(k);
  }
  const std::string shard_dir = MapDirIn(dir.path(), info.id) + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<Record> dynamic = RecordsOf(shard_dir, "dynamic");
  ASSERT_EQ(dynamic.size(), kKeys);
  ASSERT_EQ(RecordsOf(shard_dir, "lossless").size(), kKeys);
  const uint64_t victim = 5;
  for (const size_t at : testing::FindAll(testing::ReadWholeFile(file), Bytes(dynamic[victim - 1].value))) {
    testing::FlipBit(file, at + 30, 1);
  }
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  auto report = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(Db(*report, "dynamic").kept, kKeys - 1);
  EXPECT_EQ(Db(*report, "dynamic").lost, 1u);
  EXPECT_EQ(Db(*report, "lossless").kept, kKeys - 1);
  EXPECT_EQ(Db(*report, "lossless").lost, 1u);
  ASSERT_EQ(report->lost.size(), 2u);
  EXPECT_EQ(report->lost[1].file, "shard-0/data.mdb");
  EXPECT_EQ(report->lost[1].where, "lossless record of key 5");
  EXPECT_EQ(report->lost[1].what, "a lossless history without its state (its record was lost)");
  auto map = (*store)->Map("m-salvaged");
  ASSERT_TRUE(map.ok()) << map.status();
  for (uint64_t k = 1; k <= kKeys; ++k) {
    const auto got = (*map)->Snapshot(k);
    if (k == victim) {
      EXPECT_FALSE(got && !got->is_static) << "a changed model served from a damaged record";
      continue;
    }
    ASSERT_TRUE(got && got->model && got->lossless) << "state " << k;
    EXPECT_EQ(model::EncodeStateModel(*got->model), model::EncodeStateModel(*want[k].model)) << "state " << k;
    EXPECT_EQ(*got->lossless, *want[k].lossless) << "state " << k;
  }
}

// Returns the byte offset of the record with LSN `lsn` in a segment whose first record is `first`.
uint64_t RecordOffset(const std::string& bytes, uint64_t first, uint64_t lsn) {
  uint64_t offset = 0;
  for (uint64_t l = first; l < lsn; ++l) {
    const auto* p = reinterpret_cast<const uint8_t*>(bytes.data() + offset);
    offset += 16 + (uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24);
  }
  return offset;
}

// A new batch written to the map is acknowledged with LSN `lsn`.
void ExpectNextLsn(MapStore& map, uint64_t lsn) {
  ObservationBatch b;
  b.writer_id = 3;
  b.sequence = 1;
  b.time = 1.9e9;
  b.keys = {1};
  b.values = {0.0f};
  auto ack = map.Write(b);
  ASSERT_TRUE(ack.ok()) << ack.status();
  EXPECT_EQ(ack->lsn, lsn);
}

// What `kill -9` leaves in `image` of a store in `dir` whose map "m" (of `shards` shards) was filled and checkpointed
// (LSNs 1..24), then took `batches` more batches observing `keys` (LSNs 25..): those only in the log. Returns the map.
MapInfo CrashedAfterCheckpoint(const TempDir& dir, const TempDir& image, uint32_t shards, uint64_t batches,
                               uint64_t keys) {
  StoreOptions no_checkpoints;
  no_checkpoints.checkpoint_log_bytes = 1ull << 40;
  auto store = Store::Open(dir.path(), no_checkpoints);
  EXPECT_TRUE(store.ok());
  MapInfo info = Generic("m");
  info.shards = shards;
  info = *(*store)->CreateMap(info);
  auto map = *(*store)->Map("m");
  Fill(*map);
  EXPECT_TRUE(map->Checkpoint().ok());
  for (uint64_t i = 0; i < batches; ++i) {
    ObservationBatch b;
    b.writer_id = 2;
    b.sequence = i + 1;
    b.time = 1.8e9 + 60.0 * i;
    for (uint64_t k = 1; k <= keys; ++k) {
      b.keys.push_back(k);
      b.values.push_back(1.0f);
    }
    EXPECT_TRUE(map->Write(b).ok());
  }
  testing::CopyCrashImage(dir.path(), image.path());  // killed here
  return info;
}

// The only segment of a log directory.
std::string OnlySegment(const std::string& wal) {
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(wal)) segments.push_back(e.path().string());
  EXPECT_EQ(segments.size(), 1u);
  return segments.empty() ? "" : segments[0];
}

// Flips a bit in the payload of the record of LSN `lsn` of a segment; returns the record's offset.
uint64_t DamageLogRecord(const std::string& segment, uint64_t lsn) {
  const uint64_t first = std::stoull(std::filesystem::path(segment).filename().string().substr(4, 20));
  const uint64_t at = RecordOffset(testing::ReadWholeFile(segment), first, lsn);
  testing::FlipBit(segment, at + 20, 0);
  return at;
}

TEST(SalvageTest, ACorruptLogRecordKeepsTheLogBeforeItAndReportsTheRest) {
  TempDir dir, image;
  const uint64_t id = CrashedAfterCheckpoint(dir, image, 1, 20, 8).id;  // LSNs 25..44 in the log only
  const std::string segment = OnlySegment(MapDirIn(image.path(), id) + "/wal");
  const std::string log = testing::ReadWholeFile(segment);
  const uint64_t at = DamageLogRecord(segment, 35);

  auto store = Store::Open(image.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  auto report = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(report.ok()) << report.status();
  // The records after the checkpoint up to the damaged one: 25..34.
  EXPECT_EQ(report->log.records_kept, 10u);
  EXPECT_EQ(report->log.last_lsn, 34u);
  EXPECT_EQ(report->log.records_lost, 10u);  // 35 (damaged) .. 44
  EXPECT_EQ(report->log.bytes_lost, log.size() - at);
  EXPECT_EQ(report->records_lost(), 0u);
  ASSERT_EQ(report->lost.size(), 1u);
  EXPECT_EQ(report->lost[0].file, "wal/" + std::filesystem::path(segment).filename().string());
  EXPECT_EQ(report->lost[0].where, absl::StrCat("byte ", at, " (after LSN 34)"));

  auto map = (*store)->Map("m-salvaged");
  ASSERT_TRUE(map.ok()) << map.status();
  // 24 scans of every state, then 10 of states 1..8.
  EXPECT_EQ((*map)->Stats().totals.observations, 24 * kStates + 10 * 8);
  // New records go above everything kept.
  ExpectNextLsn(**map, 35);
  // The damaged log is left as it was.
  std::string expected_log = log;
  expected_log[at + 20] = static_cast<char>(expected_log[at + 20] ^ 1);
  EXPECT_EQ(testing::ReadWholeFile(segment), expected_log);

  // And the salvaged map recovers from its own log at the next start.
  store->reset();
  auto reopened = Store::Open(image.path(), {});
  ASSERT_TRUE(reopened.ok());
  auto again = (*reopened)->Map("m-salvaged");
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ((*again)->Stats().totals.observations, 24 * kStates + 10 * 8 + 1);
}

// A shard whose checkpoint LSN record was damaged: nothing says which log records it holds, so none is applied to it
// again (its checkpoint is set to the end of the kept log), and that is reported; the other shard replays the log.
TEST(SalvageTest, ALostCheckpointLsnAppliesNoLogRecordToItsShardTwice) {
  TempDir dir, image;
  const MapInfo info = CrashedAfterCheckpoint(dir, image, 2, 10, kStates);  // LSNs 25..34 in the log only
  const std::string file = MapDirIn(image.path(), info.id) + "/shard-1/data.mdb";
  const std::string key = shard_records::kLsnKey;
  const std::vector<size_t> copies = testing::FindAll(testing::ReadWholeFile(file), Bytes(key));
  ASSERT_FALSE(copies.empty());
  for (const size_t at : copies) testing::FlipBit(file, at + key.size() + 2, 5);  // in the value after the key

  auto store = Store::Open(image.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  auto report = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->log.records_kept, 10u);
  EXPECT_EQ(report->log.last_lsn, 34u);
  ASSERT_EQ(report->shards.size(), 2u);
  EXPECT_EQ(report->shards[1].databases[6].name, "meta");
  EXPECT_EQ(report->shards[1].databases[6].lost, 1u);
  bool named = false;
  for (const VerifyProblem& p : report->lost) {
    named |= p.file == "shard-1/data.mdb" && p.where == "meta record checkpoint_lsn" &&
             p.what == "the checkpoint LSN was lost; set to 34: no log record up to it is applied to this shard";
  }
  EXPECT_TRUE(named);
  auto map = (*store)->Map("m-salvaged");
  ASSERT_TRUE(map.ok()) << map.status();
  uint64_t in_shard_0 = 0;
  for (uint64_t k = 1; k <= kStates; ++k) in_shard_0 += ShardOf(k, 2) == 0;
  ASSERT_GT(in_shard_0, 0u);
  ASSERT_LT(in_shard_0, kStates);
  // Shard 0: the 24 checkpointed scans and the 10 of the log; shard 1: the checkpointed ones only.
  EXPECT_EQ((*map)->Stats().totals.observations, 24 * kStates + 10 * in_shard_0);
  // New records go above the log kept.
  ExpectNextLsn(**map, 35);
}

// A salvage that cannot write the new map's files (a full disk) fails naming the map and leaves nothing of the new map:
// no catalog record, no directory. The damaged map stays failed, and a later salvage succeeds.
TEST(SalvageTest, ASalvageThatCannotWriteLeavesNothingBehind) {
  TempDir dir, image;
  const uint64_t id = CrashedAfterCheckpoint(dir, image, 1, 20, 8).id;
  DamageLogRecord(OnlySegment(MapDirIn(image.path(), id) + "/wal"), 35);
  FaultInjectionEnv env;
  StoreOptions options;
  options.env = &env;
  auto store = Store::Open(image.path(), options);
  ASSERT_TRUE(store.ok());
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  env.FailWrites(ENOSPC);
  auto refused = (*store)->SalvageMap("m", "");
  ASSERT_FALSE(refused.ok());
  EXPECT_TRUE(absl::IsResourceExhausted(refused.status())) << refused.status();
  EXPECT_NE(refused.status().message().find("salvage of map m into m-salvaged: "), std::string::npos)
      << refused.status();
  EXPECT_TRUE(absl::IsNotFound((*store)->GetMap("m-salvaged").status()));
  EXPECT_TRUE(absl::IsNotFound((*store)->Map("m-salvaged").status()));
  std::vector<std::string> dirs;
  for (const auto& e : std::filesystem::directory_iterator(image.path() + "/maps")) dirs.push_back(e.path().string());
  EXPECT_EQ(dirs, std::vector<std::string>{MapDirIn(image.path(), id)});
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  env.FailWrites(0);
  auto report = (*store)->SalvageMap("m", "");
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->log.records_kept, 10u);
  EXPECT_TRUE((*store)->Map("m-salvaged").ok());
}

TEST(SalvageTest, ASalvagePastItsDeadlineMakesNoMap) {
  TempDir dir, image;
  const uint64_t id = CrashedAfterCheckpoint(dir, image, 1, 20, 8).id;
  DamageLogRecord(OnlySegment(MapDirIn(image.path(), id) + "/wal"), 35);
  auto store = Store::Open(image.path(), {});
  ASSERT_TRUE(store.ok());
  ASSERT_EQ((*store)->FailedMaps().size(), 1u);
  auto late = (*store)->SalvageMap("m", "", absl::InfinitePast());
  ASSERT_TRUE(absl::IsDeadlineExceeded(late.status())) << late.status();
  EXPECT_NE(late.status().message().find("the salvage did not finish by its deadline, at shard-0/data.mdb"),
            std::string::npos)
      << late.status();
  EXPECT_TRUE(absl::IsNotFound((*store)->GetMap("m-salvaged").status()));
  std::vector<std::string> dirs;
  for (const auto& e : std::filesystem::directory_iterator(image.path() + "/maps")) dirs.push_back(e.path().string());
  EXPECT_EQ(dirs, std::vector<std::string>{MapDirIn(image.path(), id)});
  EXPECT_TRUE((*store)->SalvageMap("m", "").ok());
}

}  // namespace
}  // namespace fremen::storage
