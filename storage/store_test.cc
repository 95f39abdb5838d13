#include "storage/store.h"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <thread>

#include "storage/catalog.h"
#include "storage/testing/file_damage.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::GridMap;
using testing::SweepScan;
using fremen::testing::TempDir;

TEST(StoreTest, MapsLiveAcrossRestartsAndDeleteRemovesTheirFiles) {
  TempDir dir;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok()) << store.status();
    auto a = (*store)->CreateMap(GridMap("a", 16, 16, 1, 0));
    ASSERT_TRUE(a.ok()) << a.status();
    EXPECT_GE(a->shards, 1u);
    ASSERT_TRUE((*store)->CreateMap(GridMap("b", 16, 16, 1, 1)).ok());
    EXPECT_TRUE(absl::IsAlreadyExists((*store)->CreateMap(GridMap("a", 8, 8, 1, 1)).status()));
    auto map = (*store)->Map("a");
    ASSERT_TRUE(map.ok());
    for (uint64_t i = 0; i < 20; ++i) ASSERT_TRUE((*map)->Write(SweepScan(a.value(), 1, i, 50)).ok());
  }
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  auto page = (*store)->ListMaps(0, "");
  ASSERT_TRUE(page.ok());
  ASSERT_EQ(page->maps.size(), 2u);
  auto a = (*store)->Map("a");
  ASSERT_TRUE(a.ok());
  EXPECT_EQ((*a)->Stats().totals.observations, 20u * 50);
  const std::string a_dir = MapDirIn(dir.path(), (*a)->info().id);
  EXPECT_TRUE(std::filesystem::exists(a_dir));
  a->reset();
  ASSERT_TRUE((*store)->DeleteMap("a").ok());
  EXPECT_FALSE(std::filesystem::exists(a_dir));
  EXPECT_TRUE(absl::IsNotFound((*store)->Map("a").status()));
  EXPECT_TRUE(absl::IsNotFound((*store)->DeleteMap("a")));
}

// A directory the catalog does not name (a lost catalog record, an interrupted delete) is never
// removed: it is reported, and its id is never given to a new map.
TEST(StoreTest, DirectoriesTheCatalogDoesNotNameAreReportedAndKept) {
  TempDir dir;
  { ASSERT_TRUE(Store::Open(dir.path(), {}).ok()); }
  std::filesystem::create_directories(dir.path() + "/maps/999/shard-0");
  std::filesystem::create_directories(dir.path() + "/maps/1/shard-0");  // the id the next map would get
  testing::WriteWholeFile(dir.path() + "/maps/1/shard-0/data.mdb", "someone's data");
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  EXPECT_EQ((*store)->UnknownDirectories(),
            (std::vector<std::string>{dir.path() + "/maps/1", dir.path() + "/maps/999"}));
  auto created = (*store)->CreateMap(GridMap("new", 8, 8, 1, 1));
  ASSERT_TRUE(created.ok()) << created.status();
  EXPECT_EQ(created->id, 2u);
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/maps/1/shard-0/data.mdb"), "someone's data");
  EXPECT_TRUE(std::filesystem::exists(dir.path() + "/maps/999/shard-0"));
  EXPECT_TRUE((*store)->FailedMaps().empty());
}

TEST(StoreTest, BackupUnderLoadRestoresAConsistentMap) {
  TempDir dir, backup;
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  auto info = (*store)->CreateMap(GridMap("live", 32, 32, 2, 2));
  ASSERT_TRUE(info.ok());
  auto map = *(*store)->Map("live");
  std::atomic<uint64_t> written = 0;
  std::atomic<bool> stop = false;
  std::thread writer([&] {
    for (uint64_t i = 0; !stop && i < 100000; ++i) {
      ASSERT_TRUE(map->Write(SweepScan(*info, 1, i, 64)).ok());
      written = i + 1;
    }
  });
  while (written < 200) std::this_thread::yield();
  auto backed_up = (*store)->BackupMap("live", backup.path() + "/copy");
  ASSERT_TRUE(backed_up.ok());
  EXPECT_GT(*backed_up, 0u);
  const uint64_t after_backup = written;
  stop = true;
  writer.join();
  EXPECT_TRUE(absl::IsAlreadyExists((*store)->BackupMap("live", backup.path() + "/copy").status()));

  auto restored = (*store)->RestoreMap(backup.path() + "/copy", "restored");
  ASSERT_TRUE(restored.ok()) << restored.status();
  EXPECT_NE(restored->id, info->id);
  auto copy = *(*store)->Map("restored");
  // Consistent: a whole number of the writer's batches, between those before and after the copy.
  const uint64_t observations = copy->Stats().totals.observations;
  ASSERT_EQ(observations % 64, 0u);
  EXPECT_GE(observations / 64, 200u);
  EXPECT_LE(observations / 64, after_backup);
  // And the restored map holds exactly the models of that prefix.
  TempDir reference_dir;
  auto reference = MapStore::Open(*info, reference_dir.path(), {});
  ASSERT_TRUE(reference.ok());
  for (uint64_t i = 0; i < observations / 64; ++i) ASSERT_TRUE((*reference)->Write(SweepScan(*info, 1, i, 64)).ok());
  for (uint32_t x = 0; x < 32; ++x) {
    for (uint32_t y = 0; y < 32; ++y) {
      const uint64_t key = info->grid.keys().Key(x, y, 1);
      const auto got = copy->Snapshot(key), want = (*reference)->Snapshot(key);
      ASSERT_EQ(got.has_value(), want.has_value());
      if (got && !got->is_static) {
        ASSERT_EQ(got->model->spectrum(), want->model->spectrum());
      }
    }
  }
  EXPECT_TRUE(absl::IsAlreadyExists((*store)->RestoreMap(backup.path() + "/copy", "restored").status()));
  EXPECT_TRUE(absl::IsNotFound((*store)->RestoreMap(backup.path() + "/nothing", "x").status()));
}

TEST(StoreTest, GenericMapsKeepLabelsAndAnswerTopN) {
  TempDir dir;
  uint64_t kitchen_door = 0;
  {
    auto store = Store::Open(dir.path(), {});
    ASSERT_TRUE(store.ok());
    MapInfo info;
    info.name = "doors";
    info.kind = MapKind::kGeneric;
    info.shards = 2;
    ASSERT_TRUE((*store)->CreateMap(info).ok());
    auto map = *(*store)->Map("doors");
    for (uint64_t i = 0; i < 200; ++i) {
      ObservationBatch b;
      b.writer_id = 9;
      b.sequence = i + 1;
      b.time = 1.7e9 + 600.0 * i;
      for (uint64_t id = 1; id <= 6; ++id) {
        b.keys.push_back(id * 1000003);
        b.values.push_back(id <= 2 ? 1.0f : (id == 3 ? static_cast<float>(i % 2) : 0.0f));
        if (i == 0) b.labels.push_back({id * 1000003, "door" + std::to_string(id), id <= 3 ? "kitchen" : "hall"});
      }
      ASSERT_TRUE(map->Write(b).ok());
    }
    kitchen_door = 3 * 1000003;
  }
  auto store = Store::Open(dir.path(), {});  // labels and groups come back from disk
  ASSERT_TRUE(store.ok());
  auto map = *(*store)->Map("doors");
  auto top = map->TopN("kitchen", 1.7e9 + 200 * 600.0, 2, {});
  ASSERT_TRUE(top.ok()) << top.status();
  ASSERT_EQ(top->size(), 2u);
  EXPECT_EQ((*top)[0].second, 1.0f);
  EXPECT_EQ((*top)[1].second, 1.0f);
  auto all = map->TopN("kitchen", 1.7e9, 10, {});
  ASSERT_EQ(all->size(), 3u);
  EXPECT_EQ(all->back().first, kitchen_door);
  EXPECT_NEAR(all->back().second, 0.5, 0.01);
  EXPECT_TRUE(absl::IsNotFound(map->TopN("garage", 0, 1, {}).status()));
  // The labels, listed by name, all or a group's, came back from disk too.
  auto labels = map->Labels("");
  ASSERT_TRUE(labels.ok()) << labels.status();
  ASSERT_EQ(labels->size(), 6u);
  EXPECT_EQ((*labels)[0], (StateLabel{1000003, "door1", "kitchen"}));
  EXPECT_EQ((*labels)[5], (StateLabel{6 * 1000003, "door6", "hall"}));
  auto hall = map->Labels("hall");
  ASSERT_TRUE(hall.ok());
  ASSERT_EQ(hall->size(), 3u);
  EXPECT_EQ(hall->front().name, "door4");
  EXPECT_TRUE(absl::IsNotFound(map->Labels("garage").status()));
  const auto snapshot = map->Snapshot(kitchen_door);
  ASSERT_TRUE(snapshot.has_value());
  EXPECT_EQ(snapshot->name, "door3");
  EXPECT_EQ(snapshot->group, "kitchen");
}

TEST(StoreTest, LosslessMapsReconstructThePastExactly) {
  TempDir dir;
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok());
  MapInfo info = GridMap("lossless", 4, 4, 1, 1);
  info.lossless_sampling_period = 60;
  info.lossless_origin = 1.7e9;
  ASSERT_TRUE((*store)->CreateMap(info).ok());
  auto map = *(*store)->Map("lossless");
  std::vector<uint8_t> truth;
  for (uint64_t i = 0; i < 3000; ++i) {
    ObservationBatch b;
    b.writer_id = 1;
    b.sequence = i + 1;
    b.time = 1.7e9 + 60.0 * i + 1;
    const bool v = (i / 90) % 3 == 0 || i % 17 == 0;
    truth.push_back(v);
    b.keys.push_back(info.grid.keys().Key(1, 2, 0));
    b.values.push_back(v ? 1.0f : 0.0f);
    ASSERT_TRUE(map->Write(b).ok());
  }
  ObservationBatch early;
  early.writer_id = 2;
  early.sequence = 1;
  early.time = 1.7e9 - 1;
  early.keys.push_back(info.grid.keys().Key(1, 2, 0));
  early.values.push_back(1);
  EXPECT_TRUE(absl::IsInvalidArgument(map->Submit(early, [](auto) {})));
  const auto snapshot = map->Snapshot(info.grid.keys().Key(1, 2, 0));
  ASSERT_TRUE(snapshot && snapshot->lossless);
  auto past = snapshot->lossless->Reconstruct(0, truth.size());
  ASSERT_TRUE(past.ok());
  for (size_t i = 0; i < truth.size(); ++i) {
    ASSERT_EQ((*past)[i] == model::SlotState::kOccupied, truth[i] == 1) << i;
  }
  // ε_e from the outlier set: before any update P predicts 0, so every occupied slot is an outlier.
  const double occupied = std::count(truth.begin(), truth.end(), 1);
  EXPECT_NEAR(map->Stats().estimation_error, occupied / truth.size(), 1e-12);
}

}  // namespace
}  // namespace fremen::storage
