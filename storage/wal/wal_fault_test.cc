// A map store on a disk that misbehaves (env/fault_injection_env.h): disk full, I/O errors, torn
// writes and power cuts at random points of ingest, checkpoints, publications and backups. The rule
// checked everywhere: every acknowledged batch survives, exactly once (per-state observation counts
// equal those of exactly the batches held), and nothing unacknowledged is counted twice.
//
// How a power cut is simulated in-process: the env drops every unsynced byte and directory change
// at the cut and then refuses every operation, so that the store — destroyed after the cut, like a
// dead process — can write nothing more to its log. LMDB does its own I/O, outside the env: were
// the destructor to checkpoint, LMDB would save every applied batch and hide a log that
// acknowledged before its data was durable. It does not: the store meets the cut (one more batch is
// submitted after it) and latches, and a latched store writes no checkpoint (MapStore::
// WriteError). A checkpoint already under way at the cut may still commit; it holds batches
// applied, so synced, before the cut — a state a real power cut just after that checkpoint leaves.
// Recovery is then checked against exactly the batches it holds, which shows any loss or double
// count. Every loop is seeded and bounded; nothing depends on timing for its verdict.
#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>

#include "absl/container/flat_hash_map.h"
#include "storage/env/fault_injection_env.h"
#include "storage/map_store.h"
#include "storage/testing/scans.h"
#include "storage/wal/wal.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

constexpr size_t kCells = 50;

MapInfo Map() { return testing::GridMap("faults", 32, 32, 1, 2); }

// Small segments and frequent checkpoints, so that cuts fall among rolls, checkpoints and drops.
StoreOptions FaultOptions(Env* env) {
  StoreOptions options;
  options.env = env;
  options.log_segment_bytes = 4096;
  options.checkpoint_log_bytes = 12 * 1024;
  options.log_warning = [](const std::string&) {};  // the torn tails the cuts leave are expected
  return options;
}

// One submitter with a few batches in flight (so that the committer groups them); the answers are
// collected here and checked by the test's thread.
class Ingest {
 public:
  Ingest(MapStore& store, const MapInfo& map) : store_(store), map_(map) {}
  ~Ingest() { Wait(); }

  // Submits scans, up to `window` unanswered, until `count` were submitted in all, the store
  // refuses one, or stop() holds.
  void Run(uint64_t count, size_t window = 4, const std::function<bool()>& stop = nullptr) {
    while (submitted_ < count && !(stop && stop())) {
      {
        std::unique_lock lock(mutex_);
        answered_.wait(lock, [&] { return in_flight_ < window; });
        ++in_flight_;
      }
      const uint64_t i = submitted_;
      const absl::Status s =
          store_.Submit(testing::SweepScan(map_, 1, i, kCells), [this, i](absl::StatusOr<BatchAck> a) {
            std::lock_guard lock(mutex_);
            if (a.ok()) {
              acked_.push_back(i);
            } else if (first_error_.ok()) {
              first_error_ = a.status();
            }
            --in_flight_;
            answered_.notify_all();
          });
      if (!s.ok()) {
        std::lock_guard lock(mutex_);
        --in_flight_;
        if (first_error_.ok()) first_error_ = s;
        return;
      }
      ++submitted_;
    }
  }

  void Wait() {
    std::unique_lock lock(mutex_);
    answered_.wait(lock, [&] { return in_flight_ == 0; });
  }

  uint64_t submitted() const { return submitted_; }
  // The acknowledged scans: always a prefix 0..n-1, as the log keeps submission order.
  uint64_t acked() {
    std::lock_guard lock(mutex_);
    for (size_t k = 0; k < acked_.size(); ++k) EXPECT_EQ(acked_[k], k) << "acknowledged out of order";
    return acked_.size();
  }
  absl::Status first_error() {
    std::lock_guard lock(mutex_);
    return first_error_;
  }

 private:
  MapStore& store_;
  const MapInfo map_;
  uint64_t submitted_ = 0;
  std::mutex mutex_;
  std::condition_variable answered_;
  size_t in_flight_ = 0;
  std::vector<uint64_t> acked_;
  absl::Status first_error_;
};

uint64_t Count(const std::optional<StateSnapshot>& s) {
  if (!s) return 0;
  return s->is_static ? s->static_state.count() : s->model->spectrum().count();
}

// The store holds exactly scans 0..held-1 with acked ≤ held ≤ submitted: every acknowledged batch,
// each once, and every state's count is theirs. Returns held.
uint64_t ExpectExactlyAPrefix(const MapStore& store, const MapInfo& map, uint64_t acked, uint64_t submitted,
                              const std::string& context) {
  const uint64_t observations = store.Stats().totals.observations;
  EXPECT_EQ(observations % kCells, 0u) << context;
  const uint64_t held = observations / kCells;
  EXPECT_GE(held, acked) << context << ": an acknowledged batch was lost";
  EXPECT_LE(held, submitted) << context;
  absl::flat_hash_map<uint64_t, uint64_t> want;
  for (uint64_t i = 0; i < held; ++i) {
    for (uint64_t key : testing::SweepScan(map, 1, i, kCells).keys) ++want[key];
  }
  uint64_t wrong = 0;
  for (uint32_t x = 0; x < map.grid.size[0]; ++x) {
    for (uint32_t y = 0; y < map.grid.size[1]; ++y) {
      const uint64_t key = map.grid.keys().Key(x, y, 0);
      const auto it = want.find(key);
      if (Count(store.Snapshot(key)) != (it == want.end() ? 0 : it->second)) ++wrong;
    }
  }
  EXPECT_EQ(wrong, 0u) << context << ": states whose observation count is not that of the " << held << " batches";
  return held;
}

TEST(WalFaultTest, AFailedFsyncLatchesTheLog) {
  fremen::testing::TempDir dir;
  FaultInjectionEnv env;
  WalOptions options;
  options.env = &env;
  auto wal = WalWriter::Open(dir.path(), options);
  ASSERT_TRUE(wal.ok());
  const uint8_t record[] = {1, 2, 3};
  (*wal)->Append(record);
  ASSERT_TRUE((*wal)->Sync().ok());
  env.FailSyncs(EIO);
  (*wal)->Append(record);
  EXPECT_FALSE((*wal)->Sync().ok());
  env.FailSyncs(0);
  (*wal)->Append(record);
  const absl::Status again = (*wal)->Sync();
  EXPECT_FALSE(again.ok()) << "a failed fsync leaves unknown bytes: nothing "
                              "may be acknowledged after it";
  EXPECT_NE(again.message().find("Input/output error"), std::string::npos) << again;
  EXPECT_EQ((*wal)->durable_lsn(), 1u);
}

TEST(WalFaultTest, DiskFullIsResourceExhaustedAndTheMapsWriteErrorSaysSo) {
  fremen::testing::TempDir dir;
  const MapInfo map = Map();
  FaultInjectionEnv env;
  {
    auto store = MapStore::Open(map, dir.path(), FaultOptions(&env));
    ASSERT_TRUE(store.ok());
    ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, 0, kCells)).ok());
    env.FailWrites(ENOSPC);
    const auto full = (*store)->Write(testing::SweepScan(map, 1, 1, kCells));
    ASSERT_FALSE(full.ok());
    EXPECT_TRUE(absl::IsResourceExhausted(full.status())) << full.status();
    const absl::Status error = (*store)->WriteError();
    EXPECT_TRUE(absl::IsResourceExhausted(error)) << error;
    EXPECT_NE(error.message().find("No space left on device"), std::string::npos) << error;
    // A new batch gets the error at once.
    EXPECT_TRUE(absl::IsResourceExhausted((*store)->Submit(testing::SweepScan(map, 1, 1, kCells), [](auto) {})));
  }
  // Space freed and restarted: the map takes writes again, with what was acknowledged.
  env.FailWrites(0);
  auto store = MapStore::Open(map, dir.path(), FaultOptions(&env));
  ASSERT_TRUE(store.ok()) << store.status();
  ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, 1, kCells)).ok());
  ExpectExactlyAPrefix(**store, map, 2, 2, "after ENOSPC");
}

TEST(WalFaultTest, AnIoErrorOnWriteLatchesAndNothingIsAcknowledged) {
  fremen::testing::TempDir dir;
  const MapInfo map = Map();
  FaultInjectionEnv env;
  auto store = MapStore::Open(map, dir.path(), FaultOptions(&env));
  ASSERT_TRUE(store.ok());
  ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, 0, kCells)).ok());
  env.FailWrites(EIO);
  EXPECT_FALSE((*store)->Write(testing::SweepScan(map, 1, 1, kCells)).ok());
  env.FailWrites(0);
  EXPECT_FALSE((*store)->Write(testing::SweepScan(map, 1, 1, kCells)).ok()) << "latched";
  EXPECT_NE((*store)->WriteError().message().find("Input/output error"), std::string::npos) << (*store)->WriteError();
  ExpectExactlyAPrefix(**store, map, 1, 1, "live, after EIO");
}

TEST(WalFaultTest, ATornWriteAtTheTailIsCutWithAWarningOnRecovery) {
  fremen::testing::TempDir dir;
  const MapInfo map = Map();
  FaultInjectionEnv env(3);
  {
    auto store = MapStore::Open(map, dir.path(), FaultOptions(&env));
    ASSERT_TRUE(store.ok());
    for (uint64_t i = 0; i < 5; ++i) ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, i, kCells)).ok());
    env.TearNextWrite();
    EXPECT_FALSE((*store)->Write(testing::SweepScan(map, 1, 5, kCells)).ok());
  }
  // The failed sync cut what it had written; a process that died before that cut leaves the start
  // of its record at the end of the newest segment, as here.
  std::string newest;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path() + "/wal")) {
    newest = std::max(newest, entry.path().string());
  }
  ASSERT_FALSE(newest.empty());
  {
    std::ofstream tail(newest, std::ios::binary | std::ios::app);
    tail.write("\x40\x00\x00\x00\x12\x34\x56", 7);  // a record header cut after 7 of its 16 bytes
  }
  std::vector<std::string> warnings;  // Open reports from the opening thread
  StoreOptions options = FaultOptions(&env);
  options.log_warning = [&](const std::string& line) { warnings.push_back(line); };
  {
    auto store = MapStore::Open(map, dir.path(), options);
    ASSERT_TRUE(store.ok()) << store.status();
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("torn tail of "), std::string::npos) << warnings[0];
    ExpectExactlyAPrefix(**store, map, 5, 5, "after a torn write");
    ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, 5, kCells)).ok());
  }
  warnings.clear();
  auto store = MapStore::Open(map, dir.path(), options);
  ASSERT_TRUE(store.ok()) << store.status();
  EXPECT_TRUE(warnings.empty()) << "the tail was cut once and for all: " << warnings[0];
  ExpectExactlyAPrefix(**store, map, 6, 6, "reopened");
}

// Runs `rounds` power cuts: each on a fresh map, `before` acknowledged scans, then the cut armed
// after a random number of operations, then `during(store, ingest)` (which runs the operation under
// test while batches stream in), then more batches until the cut; reopened, the map must hold a
// prefix of the scans with every acknowledged one.
void PowerCutRounds(int rounds, uint64_t seed, uint64_t max_ops,
                    const std::function<void(MapStore&, Ingest&)>& during) {
  const MapInfo map = Map();
  for (int round = 0; round < rounds; ++round) {
    const std::string context = "round " + std::to_string(round);
    std::mt19937_64 rng(seed * 1000 + round);
    fremen::testing::TempDir dir;
    FaultInjectionEnv env(rng());
    env.set_tear_at_cut(round % 2 == 1);
    uint64_t acked = 0, submitted = 0;
    {
      auto store = MapStore::Open(map, dir.path(), FaultOptions(&env));
      ASSERT_TRUE(store.ok()) << context << ": " << store.status();
      Ingest ingest(**store, map);
      ingest.Run(std::uniform_int_distribution<uint64_t>(0, 40)(rng));
      ingest.Wait();
      ASSERT_TRUE(ingest.first_error().ok()) << context << ": " << ingest.first_error();
      env.CutPowerAfter(std::uniform_int_distribution<uint64_t>(1, max_ops)(rng));
      during(**store, ingest);
      ingest.Run(ingest.submitted() + 300, 4, [&] { return env.power_cut(); });
      env.CutPower();  // if the operations ran out first
      // One more batch, so that the store meets the cut (and latches) even if the cut came from the
      // test rather than from one of its operations.
      ingest.Run(ingest.submitted() + 1);
      ingest.Wait();
      acked = ingest.acked();
      submitted = ingest.submitted();
    }  // the dead store: it can write nothing more to its log
    env.PowerOn();
    auto store = MapStore::Open(map, dir.path(), FaultOptions(&env));
    ASSERT_TRUE(store.ok()) << context << ": " << store.status();
    ExpectExactlyAPrefix(**store, map, acked, submitted, context);
    // And the map goes on.
    ASSERT_TRUE((*store)->Checkpoint().ok()) << context;
  }
}

TEST(WalFaultTest, PowerCutsAtRandomPointsOfIngestLoseNoAcknowledgedBatch) {
  PowerCutRounds(50, 1, 150, [](MapStore&, Ingest&) {});
}

TEST(WalFaultTest, PowerCutsDuringACheckpointLoseNoAcknowledgedBatch) {
  PowerCutRounds(20, 2, 8, [](MapStore& store, Ingest& ingest) {
    ingest.Run(ingest.submitted() + 6, 8);  // queued behind the checkpoint
    (void)store.Checkpoint();
  });
}

TEST(WalFaultTest, PowerCutsDuringAPublicationLoseNoAcknowledgedBatch) {
  PowerCutRounds(20, 3, 8, [](MapStore& store, Ingest& ingest) {
    ingest.Run(ingest.submitted() + 6, 8);
    (void)store.PublishModels();
  });
}

TEST(WalFaultTest, PowerCutsDuringABackupLoseNoAcknowledgedBatch) {
  fremen::testing::TempDir backups;
  int backup = 0;
  uint64_t restorable = 0;
  PowerCutRounds(20, 4, 12, [&](MapStore& store, Ingest& ingest) {
    const uint64_t acked_before = ingest.acked();
    ingest.Run(ingest.submitted() + 6, 8);
    const std::string to = backups.path() + "/" + std::to_string(backup++);
    if (!store.Backup(to).ok()) return;
    // A backup that says it succeeded holds at least what was acknowledged before it began.
    auto copy = MapStore::Open(Map(), to, {});
    ASSERT_TRUE(copy.ok()) << copy.status();
    EXPECT_GE((*copy)->Stats().totals.observations, acked_before * kCells);
    ++restorable;
  });
  std::fprintf(stderr, "%llu of 20 backups finished before their power cut\n", (unsigned long long)restorable);
}

}  // namespace
}  // namespace fremen::storage
