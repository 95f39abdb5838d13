// MapStore's contract with writers and with callers of a failed map: a batch is a duplicate only
// if it is the same batch (storage/dedup_table.h), across restarts from a checkpoint and from the
// log; and once a storage error latches, every write and every waiter for room learns it at once.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <future>
#include <string>

#include "storage/env/fault_injection_env.h"
#include "storage/map_store.h"
#include "storage/testing/open_map_store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::GridMap;
using testing::OpenOrDie;
using testing::SweepScan;
using fremen::testing::TempDir;

constexpr uint64_t kWriter = 7;
constexpr size_t kCells = 50;

// Batch `sequence` of kWriter; another `seed` gives other content under the same sequence.
ObservationBatch Scan(const MapInfo& map, uint64_t sequence, uint64_t seed = 1) {
  return SweepScan(map, kWriter, sequence - 1, kCells, seed);
}

// Sequences 1..10 of kWriter, then the checks every restart must pass: a retry is a duplicate,
// other content under a used sequence is refused naming writer and sequence, nothing changes.
void ExpectWindowKept(MapStore& store, const MapInfo& map) {
  const uint64_t observations = store.Stats().totals.observations;
  EXPECT_EQ(store.LastSequence(kWriter), 10u);
  for (uint64_t sequence : {1, 5, 10}) {
    auto retry = store.Write(Scan(map, sequence));
    ASSERT_TRUE(retry.ok()) << retry.status();
    EXPECT_TRUE(retry->duplicate) << sequence;
    auto reused = store.Write(Scan(map, sequence, /*seed=*/2));
    EXPECT_TRUE(absl::IsAlreadyExists(reused.status())) << reused.status();
    EXPECT_NE(reused.status().message().find("writer 7 sequence " + std::to_string(sequence) +
                                             " was already used for a different batch; continue after sequence 10"),
              std::string::npos)
        << reused.status();
  }
  EXPECT_EQ(store.Stats().totals.observations, observations);
}

TEST(MapStoreIngestTest, TheSameBatchTwiceIsAppliedOnceAndOtherContentUnderItsSequenceIsRefused) {
  TempDir dir;
  const MapInfo map = GridMap("m", 32, 32, 1, 2);
  auto store = OpenOrDie(map, dir.path());
  for (uint64_t s = 1; s <= 10; ++s) ASSERT_TRUE(store->Write(Scan(map, s)).ok());
  EXPECT_EQ(store->Stats().totals.observations, 10 * kCells);
  ExpectWindowKept(*store, map);
  // The refusal is the batch's ack (the map goes on), not a failure of the map.
  std::promise<absl::StatusOr<BatchAck>> answered;
  ASSERT_TRUE(store->Submit(Scan(map, 3, 2), [&](absl::StatusOr<BatchAck> ack) { answered.set_value(ack); }).ok());
  const absl::StatusOr<BatchAck> ack = answered.get_future().get();
  ASSERT_TRUE(ack.ok()) << ack.status();
  EXPECT_FALSE(ack->duplicate);
  EXPECT_EQ(ack->sequence, 3u);
  EXPECT_TRUE(absl::IsAlreadyExists(ack->error)) << ack->error;
  EXPECT_TRUE(store->WriteError().ok());
  // The writer continues after its last sequence, and a gap below it is new data.
  ASSERT_TRUE(store->Write(Scan(map, 12)).ok());
  auto gap = store->Write(Scan(map, 11));
  ASSERT_TRUE(gap.ok()) << gap.status();
  EXPECT_FALSE(gap->duplicate);
  EXPECT_EQ(store->Stats().totals.observations, 12 * kCells);
  EXPECT_EQ(store->LastSequence(kWriter), 12u);
}

TEST(MapStoreIngestTest, RestartsKeepTheWindowFromACheckpointAndFromTheLog) {
  TempDir dir, crashed;
  const MapInfo map = GridMap("m", 32, 32, 1, 2);
  StoreOptions options;
  options.checkpoint_log_bytes = 1ull << 40;  // no checkpoint but the one asked for
  {
    auto store = OpenOrDie(map, dir.path(), options);
    for (uint64_t s = 1; s <= 5; ++s) ASSERT_TRUE(store->Write(Scan(map, s)).ok());
    ASSERT_TRUE(store->Checkpoint().ok());
    for (uint64_t s = 6; s <= 10; ++s) ASSERT_TRUE(store->Write(Scan(map, s)).ok());
    // A crash image: the checkpoint has 1..5, only the log has 6..10 (no checkpoint runs now, so
    // the shard files do not change while they are copied).
    std::filesystem::copy(dir.path(), crashed.path(),
                          std::filesystem::copy_options::recursive | std::filesystem::copy_options::overwrite_existing);
  }
  {
    auto from_log = OpenOrDie(map, crashed.path(), options);
    EXPECT_EQ(from_log->Stats().totals.observations, 10 * kCells);
    ExpectWindowKept(*from_log, map);
  }
  auto from_checkpoint = OpenOrDie(map, dir.path(), options);  // closed cleanly: all checkpointed
  EXPECT_EQ(from_checkpoint->Stats().totals.observations, 10 * kCells);
  ExpectWindowKept(*from_checkpoint, map);
}

// A log whose sync can be made to fail with ENOSPC, and to block first so that the test can fill
// the queue while the committer is inside the sync.
struct FullDisk {
  std::atomic<bool> full = false;
  std::atomic<bool> hold = false;
  std::promise<void> entered, release;
  absl::Status operator()() {
    if (hold.exchange(false)) {
      entered.set_value();
      release.get_future().wait();
    }
    return full ? absl::ResourceExhaustedError("write to the write-ahead log: No space left on device")
                : absl::OkStatus();
  }
};

TEST(MapStoreIngestTest, AFullDiskIsNotBackpressureAndWakesTheWaitersForRoom) {
  TempDir dir;
  const MapInfo map = GridMap("m", 32, 32, 1, 1);
  FullDisk disk;
  FaultInjectionEnv env;
  env.set_before_sync([&] { return disk(); });
  StoreOptions options;
  options.env = &env;
  options.max_queued_observations = 80;  // a batch of kCells queues alone, a second does not fit
  auto store = OpenOrDie(map, dir.path(), options);
  ASSERT_TRUE(store->Write(Scan(map, 1)).ok());

  disk.full = true;
  disk.hold = true;
  std::promise<absl::StatusOr<BatchAck>> first, second;
  ASSERT_TRUE(store->Submit(Scan(map, 2), [&](absl::StatusOr<BatchAck> a) { first.set_value(a); }).ok());
  disk.entered.get_future().wait();  // the committer syncs batch 2; batch 3 queues
  ASSERT_TRUE(store->Submit(Scan(map, 3), [&](absl::StatusOr<BatchAck> a) { second.set_value(a); }).ok());
  const absl::Status full_queue = store->Submit(Scan(map, 4), [](auto) { FAIL() << "refused: never called"; });
  EXPECT_TRUE(IsQueueFull(full_queue)) << full_queue;
  std::promise<void> room;
  store->OnRoom(kCells, [&] { room.set_value(); });
  disk.release.set_value();

  // The failed sync latches: the waiter is woken although the queue did not drain for room.
  room.get_future().wait();
  const absl::StatusOr<BatchAck> failed = first.get_future().get();
  EXPECT_TRUE(absl::IsResourceExhausted(failed.status())) << failed.status();
  EXPECT_TRUE(absl::IsResourceExhausted(second.get_future().get().status()));
  // From now on every write is refused at once with the storage error — not as backpressure.
  const absl::Status refused = store->Submit(Scan(map, 4), [](auto) { FAIL() << "refused: never called"; });
  EXPECT_TRUE(absl::IsResourceExhausted(refused)) << refused;
  EXPECT_FALSE(IsQueueFull(refused));
  EXPECT_NE(refused.message().find("No space left on device"), std::string::npos) << refused;
  EXPECT_NE(refused.message().find("map m refuses writes"), std::string::npos) << refused;
  std::promise<void> at_once;
  store->OnRoom(1u << 30, [&] { at_once.set_value(); });
  EXPECT_EQ(at_once.get_future().wait_for(std::chrono::seconds(0)), std::future_status::ready);
  EXPECT_EQ(store->Stats().totals.observations, kCells);

  // Space freed, the map reopened: the acknowledged batch is there, and the writer goes on.
  disk.full = false;
  store.reset();
  auto reopened = OpenOrDie(map, dir.path());
  EXPECT_EQ(reopened->Stats().totals.observations, kCells);
  EXPECT_EQ(reopened->LastSequence(kWriter), 1u);
  auto next = reopened->Write(Scan(map, 2));
  ASSERT_TRUE(next.ok()) << next.status();
  EXPECT_FALSE(next->duplicate);
}

TEST(MapStoreIngestTest, AnIoErrorRefusesWritesWithUnavailableNamingTheCause) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 1, 1);
  std::atomic<bool> failing = false;
  FaultInjectionEnv env;
  env.set_before_sync([&]() -> absl::Status {
    return failing ? absl::InternalError("fdatasync of the write-ahead log: Input/output error") : absl::OkStatus();
  });
  StoreOptions options;
  options.env = &env;
  auto store = OpenOrDie(map, dir.path(), options);
  ASSERT_TRUE(store->Write(Scan(map, 1)).ok());
  failing = true;
  EXPECT_FALSE(store->Write(Scan(map, 2)).ok());
  const absl::Status refused = store->Submit(Scan(map, 3), [](auto) { FAIL() << "refused: never called"; });
  EXPECT_TRUE(absl::IsUnavailable(refused)) << refused;
  EXPECT_NE(refused.message().find("map m refuses writes"), std::string::npos) << refused;
  EXPECT_NE(refused.message().find("fdatasync of the write-ahead log: Input/output error"), std::string::npos)
      << refused;
}

}  // namespace
}  // namespace fremen::storage
