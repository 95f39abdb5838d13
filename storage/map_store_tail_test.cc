// An online move's tail (MapStore::StartTail, Tail, ApplyTail; docs/fleet.md, "The protocol"):
// the batches logged after a backup taken while writes go on, applied to a copy restored incoming,
// give the same map — states, models, the writers' deduplication windows.
#include <gtest/gtest.h>

#include "storage/map_store.h"
#include "storage/testing/open_map_store.h"
#include "storage/testing/scans.h"
#include "absl/strings/str_cat.h"
#include "storage/env/env.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::GridMap;
using testing::OpenOrDie;
using testing::SweepScan;
using fremen::testing::TempDir;

TEST(MapStoreTailTest, TheBatchesAfterTheSnapshotMakeTheIncomingCopyEqualToTheSource) {
  TempDir dir;
  const MapInfo map = GridMap("m", 32, 32, 1, 2);
  auto source = OpenOrDie(map, dir.path() + "/source");
  for (uint64_t i = 0; i < 5; ++i) ASSERT_TRUE(source->Write(SweepScan(map, 1, i, 300)).ok());
  EXPECT_TRUE(absl::IsFailedPrecondition(source->Tail(0).status()));  // no tail started
  ASSERT_TRUE(source->StartTail().ok());
  EXPECT_EQ(source->Move().state, MoveState::kCopying);
  uint64_t lsn = 0;
  ASSERT_TRUE(source->Backup(dir.path() + "/copy", &lsn).ok());
  EXPECT_EQ(lsn, 5u);
  // Writes go on; a retry is a duplicate (not logged, so not in the tail); the job is refused.
  for (uint64_t i = 5; i < 9; ++i) ASSERT_TRUE(source->Write(SweepScan(map, 1, i, 300)).ok());
  ASSERT_TRUE(source->Write(SweepScan(map, 2, 0, 300)).ok());
  EXPECT_TRUE(source->Write(SweepScan(map, 1, 6, 300))->duplicate);
  EXPECT_TRUE(absl::IsUnavailable(source->PublishModels().status()));
  EXPECT_TRUE(absl::IsFailedPrecondition(source->Tail(lsn).status())) << "writes not stopped yet";
  ASSERT_TRUE(source->StopWrites().ok());
  auto tail = source->Tail(lsn);
  ASSERT_TRUE(tail.ok()) << tail.status();
  ASSERT_EQ(tail->size(), 5u);
  for (size_t i = 0; i < tail->size(); ++i) EXPECT_EQ((*tail)[i].lsn, lsn + 1 + i);

  // The copy, restored with its marker, refuses writes until the tail is applied — across a reopen.
  ASSERT_TRUE(WriteFileAtomically(Env::Default(), dir.path() + "/copy/" + kIncomingFile, absl::StrCat(lsn)).ok());
  {
    auto copy = OpenOrDie(map, dir.path() + "/copy");
    EXPECT_EQ(copy->Move().state, MoveState::kIncoming);
    EXPECT_TRUE(absl::IsUnavailable(copy->Write(SweepScan(map, 3, 0, 10)).status()));
  }
  auto copy = OpenOrDie(map, dir.path() + "/copy");
  EXPECT_EQ(copy->Move().state, MoveState::kIncoming);
  EXPECT_EQ(copy->Move().snapshot_lsn, lsn);
  EXPECT_TRUE(absl::IsFailedPrecondition(copy->ApplyTail(lsn - 1, *tail)));  // another snapshot's
  ASSERT_TRUE(copy->ApplyTail(lsn, *tail).ok());
  EXPECT_EQ(copy->Move().state, MoveState::kServing);
  EXPECT_EQ(copy->Stats().totals.observations, source->Stats().totals.observations);
  EXPECT_EQ(copy->LastSequence(1), 9u);
  EXPECT_EQ(copy->LastSequence(2), 1u);
  EXPECT_TRUE(copy->Write(SweepScan(map, 1, 8, 300))->duplicate);
  for (uint64_t key = 0; key < 32 * 32; key += 7) {
    const auto a = source->Snapshot(key), b = copy->Snapshot(key);
    ASSERT_EQ(a.has_value(), b.has_value()) << key;
    if (a && !a->is_static) {
      EXPECT_EQ(a->model->spectrum(), b->model->spectrum()) << key;
    }
  }
  EXPECT_TRUE(absl::IsFailedPrecondition(copy->ApplyTail(lsn, *tail)));  // serving already
}

TEST(MapStoreTailTest, ATailThatDoesNotFollowItsSnapshotIsDataLoss) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 1, 1);
  auto source = OpenOrDie(map, dir.path() + "/source");
  ASSERT_TRUE(source->Write(SweepScan(map, 1, 0, 100)).ok());
  ASSERT_TRUE(source->StartTail().ok());
  uint64_t lsn = 0;
  ASSERT_TRUE(source->Backup(dir.path() + "/copy", &lsn).ok());
  ASSERT_TRUE(WriteFileAtomically(Env::Default(), dir.path() + "/copy/" + kIncomingFile, absl::StrCat(lsn)).ok());
  auto copy = OpenOrDie(map, dir.path() + "/copy");
  // The snapshot's own batch, claimed to follow it.
  const std::vector<TailRecord> replayed = {{lsn + 1, EncodeBatch(SweepScan(map, 1, 0, 100))}};
  EXPECT_TRUE(absl::IsDataLoss(copy->ApplyTail(lsn, replayed)));
  const std::vector<TailRecord> garbage = {{lsn + 1, "not a batch"}};
  EXPECT_TRUE(absl::IsDataLoss(copy->ApplyTail(lsn, garbage)));
  EXPECT_EQ(copy->Move().state, MoveState::kIncoming) << "a failed tail leaves the copy unserved";
}

TEST(MapStoreTailTest, ATailLargerThanItsBoundIsGivenUpAndResumingWritesDropsIt) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 1, 1);
  StoreOptions options;
  options.max_tail_bytes = 1000;
  auto store = OpenOrDie(map, dir.path(), options);
  ASSERT_TRUE(store->StartTail().ok());
  ASSERT_TRUE(store->Backup(dir.path() + "-copy").ok());
  for (uint64_t i = 0; i < 3; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 100)).ok());
  ASSERT_TRUE(store->StopWrites().ok());
  const absl::Status given_up = store->Tail(0).status();
  EXPECT_TRUE(absl::IsFailedPrecondition(given_up)) << given_up;
  EXPECT_NE(given_up.message().find("more than 1000 bytes"), std::string::npos) << given_up;
  // Resuming writes drops the record; a new copy starts a new one.
  ASSERT_TRUE(store->ResumeWrites().ok());
  EXPECT_EQ(store->Move().state, MoveState::kServing);
  ASSERT_TRUE(store->StartTail().ok());
  EXPECT_TRUE(store->Write(SweepScan(map, 1, 3, 10)).ok());
  ASSERT_TRUE(store->StopWrites().ok());
  auto tail = store->Tail(0);
  ASSERT_TRUE(tail.ok()) << tail.status();
  EXPECT_EQ(tail->size(), 1u);
}

}  // namespace
}  // namespace fremen::storage
