#include "storage/map_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <filesystem>
#include <random>
#include <thread>

#include "storage/env/fault_injection_env.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/model/kernels/compact_models.h"
#include "storage/model/phasor.h"
#include "storage/model/kernels/region_predict.h"
#include "storage/testing/open_map_store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::GridMap;
using testing::OpenOrDie;
using testing::SweepScan;
using fremen::testing::TempDir;

// Every state's model, as a comparable string of its encodings.
void ExpectSameModels(const MapStore& a, const MapStore& b, const MapInfo& map) {
  size_t compared = 0, dynamic = 0;
  for (uint32_t x = 0; x < map.grid.size[0]; ++x) {
    for (uint32_t y = 0; y < map.grid.size[1]; ++y) {
      for (uint32_t z = 0; z < map.grid.size[2]; ++z) {
        const uint64_t key = map.grid.keys().Key(x, y, z);
        const auto sa = a.Snapshot(key), sb = b.Snapshot(key);
        ASSERT_EQ(sa.has_value(), sb.has_value()) << x << "," << y << "," << z;
        if (!sa) continue;
        ++compared;
        ASSERT_EQ(sa->is_static, sb->is_static) << key;
        if (sa->is_static) {
          EXPECT_EQ(sa->static_state, sb->static_state) << key;
        } else {
          ++dynamic;
          EXPECT_EQ(sa->model->spectrum(), sb->model->spectrum()) << key;
          EXPECT_EQ(sa->model->persistence(), sb->model->persistence()) << key;
          EXPECT_EQ(sa->model->order_errors(), sb->model->order_errors()) << key;
          EXPECT_EQ(sa->model->has_published(), sb->model->has_published()) << key;
          EXPECT_EQ(sa->model->published(), sb->model->published()) << key;
        }
      }
    }
  }
  EXPECT_GT(compared, 0u);
  EXPECT_GT(dynamic, 0u);
}

TEST(MapStoreTest, AcknowledgesWithCountsAndAppliesExactlyOnce) {
  TempDir dir;
  const MapInfo map = GridMap("m", 32, 32, 2, 2);
  auto store = OpenOrDie(map, dir.path());
  ObservationBatch scan = SweepScan(map, 1, 0, 500);
  scan.values[3] = 2.0f;  // rejected, the rest applied
  auto ack = store->Write(scan);
  ASSERT_TRUE(ack.ok()) << ack.status();
  EXPECT_EQ(ack->accepted, 499u);
  EXPECT_EQ(ack->rejected, 1u);
  EXPECT_FALSE(ack->duplicate);
  const uint64_t observations = store->Stats().totals.observations;
  EXPECT_EQ(observations, 499u);
  auto again = store->Write(scan);  // a robot's retry after a reconnect
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(again->duplicate);
  EXPECT_EQ(store->Stats().totals.observations, observations);
}

TEST(MapStoreTest, BadBatchesGetPreciseErrorsAndNothingIsApplied) {
  TempDir dir;
  const MapInfo map = GridMap("m", 8, 8, 1, 1);
  auto store = OpenOrDie(map, dir.path());
  ObservationBatch bad = SweepScan(map, 1, 0, 10);
  bad.time = INFINITY;
  EXPECT_TRUE(absl::IsInvalidArgument(store->Submit(bad, [](auto) { FAIL() << "must not be called"; })));
  bad = SweepScan(map, 1, 0, 10);
  bad.patch.size = {9, 1, 1};
  bad.patch.values.assign(9, 0);
  EXPECT_TRUE(absl::IsOutOfRange(store->Submit(bad, [](auto) { FAIL() << "must not be called"; })));
  EXPECT_EQ(store->Stats().totals.observations, 0u);
}

TEST(MapStoreTest, RestartRecoversFromCheckpointAndLogToTheSameModels) {
  TempDir dir, reference_dir;
  const MapInfo map = GridMap("m", 24, 24, 3, 2);
  StoreOptions options;
  options.checkpoint_log_bytes = 40000;  // several checkpoints along the way
  auto reference = OpenOrDie(map, reference_dir.path());
  {
    auto store = OpenOrDie(map, dir.path(), options);
    for (uint64_t i = 0; i < 300; ++i) {
      ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 200)).ok());
      ASSERT_TRUE(reference->Write(SweepScan(map, 1, i, 200)).ok());
      if (i == 150 || i == 280) {  // the nightly update, logged among the batches
        ASSERT_TRUE(store->PublishModels().ok());
        ASSERT_TRUE(reference->PublishModels().ok());
      }
    }
    // Destroyed without a final checkpoint of what the log holds? Close checkpoints; the crash
    // test covers the other case.
  }
  auto reopened = OpenOrDie(map, dir.path(), options);
  ExpectSameModels(*reopened, *reference, map);
  auto retry = reopened->Write(SweepScan(map, 1, 299, 200));
  ASSERT_TRUE(retry.ok());
  EXPECT_TRUE(retry->duplicate);  // the dedup table survived too
}

// Recovery applies the log in groups of batches (every shard on its own thread), a publication
// ending its group: a log of many groups, publications among them, replays to the models of a
// store that applied the same batches live.
TEST(MapStoreTest, ALogOfManyGroupsReplaysToTheSameModels) {
  TempDir dir, image_dir, reference_dir;
  const MapInfo map = GridMap("m", 24, 24, 3, 2);
  StoreOptions never;
  never.checkpoint_log_bytes = UINT64_MAX;  // everything stays in the log
  auto reference = OpenOrDie(map, reference_dir.path());
  auto store = OpenOrDie(map, dir.path(), never);
  for (uint64_t i = 0; i < 1500; ++i) {  // about three groups of 512 records
    ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 100)).ok());
    ASSERT_TRUE(reference->Write(SweepScan(map, 1, i, 100)).ok());
    if (i == 200 || i == 511 || i == 1100) {
      ASSERT_TRUE(store->PublishModels().ok());
      ASSERT_TRUE(reference->PublishModels().ok());
    }
  }
  // A crash image: the files as they are while the store is open, every batch acknowledged and so
  // in the log, no checkpoint since the map was created.
  std::filesystem::copy(dir.path(), image_dir.path() + "/map", std::filesystem::copy_options::recursive);
  auto recovered = OpenOrDie(map, image_dir.path() + "/map", never);
  EXPECT_EQ(recovered->Stats().totals.observations, reference->Stats().totals.observations);
  ExpectSameModels(*recovered, *reference, map);
}

// A never-changed cell keeps its first and last observation and its count whatever the order of
// its scans: the fast path for a static cell seen again in time order must leave one observed
// before its last (a robot's late scan) to the general rule, which moves the first observation
// back and leaves the last where it was. Several cells a batch, so that they form a run.
TEST(MapStoreTest, AStaticCellSeenAgainOutOfTimeOrderKeepsItsFirstAndLastObservation) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 1, 1, 1);
  auto store = OpenOrDie(map, dir.path());
  const double t0 = 1.7e9;
  const double times[] = {t0 + 100, t0 + 200, t0 + 50, t0 + 150, t0 + 300};
  uint64_t sequence = 0;
  for (double t : times) {
    ObservationBatch b;
    b.writer_id = 1;
    b.sequence = ++sequence;
    b.time = t;
    for (uint32_t x = 0; x < 16; ++x) {
      b.keys.push_back(map.grid.keys().Key(x, 0, 0));
      b.values.push_back(x % 2 ? 1.0f : 0.0f);
    }
    auto ack = store->Write(std::move(b));
    ASSERT_TRUE(ack.ok()) << ack.status();
  }
  for (uint32_t x = 0; x < 16; ++x) {
    const auto snapshot = store->Snapshot(map.grid.keys().Key(x, 0, 0));
    ASSERT_TRUE(snapshot.has_value()) << x;
    ASSERT_TRUE(snapshot->is_static) << x;
    EXPECT_EQ(snapshot->static_state.count(), 5u) << x;
    EXPECT_EQ(snapshot->static_state.value(), x % 2 ? 1.0f : 0.0f) << x;
    EXPECT_EQ(snapshot->static_state.t_first, t0 + 50) << x;
    EXPECT_EQ(snapshot->static_state.t_last(), t0 + 300) << x;
  }
}

TEST(MapStoreTest, PredictionsMatchTheModelsAndRegionsMatchPoints) {
  TempDir dir;
  const MapInfo map = GridMap("m", 40, 20, 2, 2);
  auto store = OpenOrDie(map, dir.path());
  for (uint64_t i = 0; i < 500; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 300)).ok());
  auto published = store->PublishModels();
  ASSERT_TRUE(published.ok());
  EXPECT_GT(*published, 0u);
  const double t = 1.7e9 + 500 * 600.0 + 3600;
  CellBox box{{3, 2, 0}, {37, 19, 2}};
  std::vector<float> region;
  ASSERT_TRUE(store->PredictBox(box, t, {}, region).ok());
  ASSERT_EQ(region.size(), box.cell_count());
  size_t i = 0, unobserved = 0;
  for (uint32_t z = box.lo[2]; z < box.hi[2]; ++z) {
    for (uint32_t y = box.lo[1]; y < box.hi[1]; ++y) {
      for (uint32_t x = box.lo[0]; x < box.hi[0]; ++x, ++i) {
        const uint64_t key = map.grid.keys().Key(x, y, z);
        const double times[] = {t};
        const float point = store->Predict({&key, 1}, times, {})[0];
        ASSERT_EQ(region[i], point) << x << "," << y << "," << z;
        const auto snapshot = store->Snapshot(key);
        if (!snapshot) {
          ++unobserved;
          EXPECT_EQ(point, kUnobservedProbability);
        } else if (snapshot->is_static) {
          EXPECT_EQ(point, snapshot->static_state.value());
        } else {
          ASSERT_TRUE(snapshot->model->has_published());
          EXPECT_NEAR(point, snapshot->model->Predict(t), 1e-5);
        }
      }
    }
  }
  std::vector<float> out;
  EXPECT_TRUE(absl::IsOutOfRange(store->PredictBox({{0, 0, 0}, {41, 1, 1}}, t, {}, out)));
  EXPECT_TRUE(absl::IsOutOfRange(store->PredictBox({{5, 0, 0}, {5, 1, 1}}, t, {}, out)));
  // Into the caller's memory (a response's values): the same p, every value written (the memory's
  // old contents are not 0.5 or any p), and only into memory of the box's size.
  std::vector<float> in_place(box.cell_count(), -1.0f);
  ASSERT_TRUE(store->PredictBox(box, t, {}, std::span<float>(in_place)).ok());
  EXPECT_EQ(in_place, region);
  std::vector<float> short_by_one(box.cell_count() - 1);
  const absl::Status wrong_size = store->PredictBox(box, t, {}, std::span<float>(short_by_one));
  EXPECT_TRUE(absl::IsInvalidArgument(wrong_size)) << wrong_size;
  EXPECT_NE(wrong_size.message().find("out holds"), std::string::npos) << wrong_size;
}

// A box query and a point query answer a published state by the region kernel the benchmark measures
// (model/region_predict.h): bit for bit what the kernel gives for the same models, at each state's
// own order and at fixed ones.
TEST(MapStoreTest, PredictionsOfPublishedStatesAreTheRegionKernelsBitForBit) {
  TempDir dir;
  const MapInfo map = GridMap("m", 40, 20, 2, 3);
  auto store = OpenOrDie(map, dir.path());
  for (uint64_t i = 0; i < 300; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 300)).ok());
  ASSERT_TRUE(store->PublishModels().ok());
  const int max_order = store->settings().max_order;
  const CellBox box{{0, 0, 0}, map.grid.size};
  std::vector<uint64_t> keys;
  std::vector<size_t> cells;  // index in the box of each published state
  model::CompactModels models(max_order);
  for (uint32_t z = 0, i = 0; z < box.hi[2]; ++z) {
    for (uint32_t y = 0; y < box.hi[1]; ++y) {
      for (uint32_t x = 0; x < box.hi[0]; ++x, ++i) {
        const uint64_t key = map.grid.keys().Key(x, y, z);
        const auto snapshot = store->Snapshot(key);
        if (!snapshot || snapshot->is_static || !snapshot->model->has_published()) continue;
        models.Resize(keys.size() + 1);
        models.Set(keys.size(), snapshot->model->published());
        keys.push_back(key);
        cells.push_back(i);
      }
    }
  }
  ASSERT_GT(keys.size(), 100u);
  const double t = 1.7e9 + 300 * 600.0 + 5000;
  const model::PhasorTable table(store->settings().periods, t);
  std::vector<float> kernel(keys.size()), region;
  for (int order = -1; order <= max_order + 1; ++order) {
    PredictOptions options;
    options.order = order;
    model::PredictRegion(models, table, order, kernel.data());
    ASSERT_TRUE(store->PredictBox(box, t, options, region).ok());
    const std::vector<float> points = store->Predict(keys, {&t, 1}, options);
    for (size_t j = 0; j < keys.size(); ++j) {
      ASSERT_EQ(region[cells[j]], kernel[j]) << "cell " << cells[j] << " order " << order;
      ASSERT_EQ(points[j], kernel[j]) << "cell " << cells[j] << " order " << order;
    }
  }
}

// Predict asks each shard once for all its keys, batches their published models through the kernel
// and, from kParallelPredictions keys, runs the shards on their own threads: the answer must be what
// asking key by key gives, at each time, in the caller's order (shuffled, with repeats and keys never
// observed), and PredictWithObserved's flags must be Observed's.
TEST(MapStoreTest, BatchedPredictionsEqualOneKeyAtATimeInTheCallersOrder) {
  TempDir dir;
  const MapInfo map = GridMap("m", 300, 300, 1, 3);
  auto store = OpenOrDie(map, dir.path());
  for (uint64_t i = 0; i < 200; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 2000)).ok());
  ASSERT_TRUE(store->PublishModels().ok());
  for (uint64_t i = 200; i < 230; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 2000)).ok());  // unpublished news

  std::vector<uint64_t> keys;
  for (uint32_t y = 0; y < 300; ++y) {
    for (uint32_t x = 0; x < 300; ++x) keys.push_back(map.grid.keys().Key(x, y, 0));
  }
  for (size_t i = 0; i < 5000; ++i) keys.push_back(keys[(i * 7919) % keys.size()]);  // repeats
  std::shuffle(keys.begin(), keys.end(), std::mt19937_64(7));
  ASSERT_GE(keys.size(), 1u << 16);  // the parallel path
  const std::vector<double> times = {1.7e9 + 3600, 1.7e9 + 200 * 600.0 + 5000, 1.7e9 + 86400 * 3};
  const std::vector<uint8_t> flags = store->Observed(keys);
  size_t observed = 0;
  for (uint8_t f : flags) observed += f;
  ASSERT_GT(observed, 1000u);
  ASSERT_LT(observed, keys.size());  // some never observed
  for (const bool persistence : {false, true}) {
    PredictOptions options;
    options.persistence = persistence;
    std::vector<uint8_t> observed_flags;
    const std::vector<float> batched = store->PredictWithObserved(keys, times, options, observed_flags);
    ASSERT_EQ(batched, store->Predict(keys, times, options));
    ASSERT_EQ(observed_flags, flags);
    ASSERT_EQ(batched.size(), keys.size() * times.size());
    for (size_t j = 0; j < times.size(); ++j) {
      for (size_t i = 0; i < keys.size(); i += 97) {
        ASSERT_EQ(batched[j * keys.size() + i], store->Predict({&keys[i], 1}, {&times[j], 1}, options)[0])
            << "key " << keys[i] << " time " << times[j] << " persistence " << persistence;
      }
    }
  }
}

TEST(MapStoreTest, GrowsATinyLmdbMapInsteadOfFailing) {
  TempDir dir;
  const MapInfo map = GridMap("m", 64, 64, 1, 1);
  StoreOptions options;
  options.initial_map_size = 64 << 10;
  options.checkpoint_log_bytes = 1 << 16;
  auto store = OpenOrDie(map, dir.path(), options);
  for (uint64_t i = 0; i < 200; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 400)).ok());
  ASSERT_TRUE(store->Checkpoint().ok());
  const MapStats stats = store->Stats();
  EXPECT_GT(stats.totals.disk_bytes, 64u << 10);
  // What the metrics export: each growth doubled the map, and is counted.
  EXPECT_GT(stats.lmdb_growths, 0u);
  EXPECT_EQ(stats.lmdb_map_size_bytes, (uint64_t{64} << 10) << stats.lmdb_growths);
  EXPECT_EQ(stats.queued_observations, 0u);  // every batch was written, so none is queued
}

TEST(MapStoreTest, ConcurrentReadersDuringWrites) {
  TempDir dir;
  const MapInfo map = GridMap("m", 32, 32, 1, 2);
  StoreOptions options;
  options.checkpoint_log_bytes = 50000;
  auto store = OpenOrDie(map, dir.path(), options);
  std::atomic<bool> done = false;
  std::vector<std::thread> readers;
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&] {
      std::vector<float> region;
      while (!done) {
        ASSERT_TRUE(store->PredictBox({{0, 0, 0}, {32, 32, 1}}, 1.7e9, {true, -1}, region).ok());
        for (float p : region) ASSERT_TRUE(p >= 0 && p <= 1);
        (void)store->Stats();
      }
    });
  }
  for (uint64_t i = 0; i < 300; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 100)).ok());
  done = true;
  for (auto& t : readers) t.join();
}

TEST(MapStoreTest, CorruptedRecordIsDataLossNotACrash) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 1, 1);
  {
    auto store = OpenOrDie(map, dir.path());
    for (uint64_t i = 0; i < 100; ++i) ASSERT_TRUE(store->Write(SweepScan(map, 1, i, 100)).ok());
  }
  {
    LmdbOptions options;
    options.databases = {"dynamic"};
    auto env = LmdbEnv::Open(dir.path() + "/shard-0", options);
    ASSERT_TRUE(env.ok());
    ASSERT_TRUE((*env)->Write([](LmdbTxn& txn) -> absl::Status {
      auto db = txn.Db("dynamic");
      if (!db.ok()) return db.status();
      std::vector<std::pair<std::vector<uint8_t>, std::vector<uint8_t>>> damaged;
      (void)txn.Scan(*db, {}, {}, [&](auto k, auto v) {
        std::vector<uint8_t> value(v.begin(), v.end());
        value[value.size() / 2] ^= 0xFF;
        value.resize(value.size() - 3);
        damaged.emplace_back(std::vector<uint8_t>(k.begin(), k.end()), value);
        return false;  // one record is enough
      });
      for (auto& [k, v] : damaged) {
        if (auto s = txn.Put(*db, k, v); !s.ok()) return s;
      }
      return absl::OkStatus();
    }).ok());
  }
  auto reopened = MapStore::Open(map, dir.path(), {});
  ASSERT_FALSE(reopened.ok());
  EXPECT_TRUE(absl::IsDataLoss(reopened.status())) << reopened.status();
  EXPECT_NE(reopened.status().message().find("dynamic"), std::string::npos) << reopened.status();
}

}  // namespace
}  // namespace fremen::storage

namespace fremen::storage {
namespace {

TEST(MapStoreTest, AFailedLogSyncIsNeverAcknowledgedAndLatches) {
  fremen::testing::TempDir dir;
  const MapInfo map = testing::GridMap("m", 16, 16, 1, 1);
  FaultInjectionEnv env;
  StoreOptions options;
  options.env = &env;
  auto store = MapStore::Open(map, dir.path(), options);
  ASSERT_TRUE(store.ok());
  ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, 0, 50)).ok());
  EXPECT_TRUE((*store)->WriteError().ok());
  env.FailSyncs(EIO);
  const auto failed = (*store)->Write(testing::SweepScan(map, 1, 1, 50));
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.status().message().find("injected"), std::string::npos) << failed.status();
  EXPECT_NE((*store)->WriteError().message().find("injected"), std::string::npos);
  env.FailSyncs(0);  // even once the disk recovers, what was written is unknown: writes stay refused
  EXPECT_FALSE((*store)->Write(testing::SweepScan(map, 1, 2, 50)).ok());
  // Reads go on, and see exactly the acknowledged batch.
  EXPECT_EQ((*store)->Stats().totals.observations, 50u);
  env.CutPower();  // the unsynced record goes with the page cache
  store->reset();
  env.PowerOn();
  auto reopened = MapStore::Open(map, dir.path(), options);
  ASSERT_TRUE(reopened.ok()) << reopened.status();
  EXPECT_EQ((*reopened)->Stats().totals.observations, 50u);
}

}  // namespace
}  // namespace fremen::storage

namespace fremen::storage {
namespace {

TEST(MapStoreTest, RefusesWhenBehindAndCallsBackWhenThereIsRoom) {
  fremen::testing::TempDir dir;
  const MapInfo map = testing::GridMap("m", 64, 64, 1, 1);
  StoreOptions options;
  options.max_queued_observations = 1000;
  auto store = MapStore::Open(map, dir.path(), options);
  ASSERT_TRUE(store.ok());
  std::atomic<int> acked = 0;
  int refused = 0;
  std::atomic<bool> room = false;
  for (uint64_t i = 0; i < 200 && refused == 0; ++i) {
    ObservationBatch scan = testing::SweepScan(map, 1, i, 900);
    const uint64_t n = scan.observation_count();
    const absl::Status s = (*store)->Submit(std::move(scan), [&](auto ack) {
      EXPECT_TRUE(ack.ok());
      ++acked;
    });
    if (absl::IsResourceExhausted(s)) {
      ++refused;
      // The queue holds a 900-observation batch: a second does not fit until the committer takes it.
      (*store)->OnRoom(n, [&] { room = true; });
    }
  }
  ASSERT_EQ(refused, 1) << "200 batches of 900 against a queue of 1000 must overflow once";
  while (!room) std::this_thread::yield();
  EXPECT_TRUE((*store)->Checkpoint().ok());
  EXPECT_GT(acked.load(), 0);
}

TEST(MapStoreTest, ObservedLabelsAndPublicationProgress) {
  fremen::testing::TempDir dir;
  const MapInfo map = testing::GridMap("m", 32, 32, 1, 2);
  auto store = MapStore::Open(map, dir.path(), {});
  ASSERT_TRUE(store.ok());
  for (uint64_t i = 0; i < 100; ++i) ASSERT_TRUE((*store)->Write(testing::SweepScan(map, 1, i, 200)).ok());
  const ObservationBatch first = testing::SweepScan(map, 1, 0, 200);
  const uint64_t keys[] = {first.keys[0], map.grid.keys().Key(31, 31, 0) + (uint64_t{1} << 40)};
  const auto observed = (*store)->Observed(keys);
  EXPECT_EQ(observed[0], 1);
  EXPECT_EQ(observed[1], 0);
  uint64_t last_done = 0, last_total = 0;
  auto published = (*store)->PublishModels([&](uint64_t done, uint64_t total) {
    EXPECT_GE(done, last_done);
    last_done = done;
    last_total = total;
  });
  ASSERT_TRUE(published.ok());
  EXPECT_EQ(last_done, *published);
  EXPECT_EQ(last_total, *published);
  EXPECT_FALSE((*store)->Label(first.keys[0]).has_value());
}

}  // namespace
}  // namespace fremen::storage

namespace fremen::storage {
namespace {

// States past the widening limit fold in double (model/wide_bodies.h); the limit is lowered from
// 2^20 to 100 observations so that the test runs in a second.
TEST(MapStoreTest, StatesPastTheWideningLimitFoldInDoubleAndRecoverExactly) {
  TempDir dir, reference_dir, float_dir;
  const MapInfo map = GridMap("m", 4, 4, 1, 2);
  StoreOptions options;
  options.widen_records_at = 100;
  options.checkpoint_log_bytes = 20000;  // checkpoints along the way write the double bodies
  auto reference = OpenOrDie(map, reference_dir.path(), options);
  auto all_float = OpenOrDie(map, float_dir.path());  // never widens at these counts
  auto store = OpenOrDie(map, dir.path(), options);
  for (uint64_t i = 0; i < 240; ++i) {
    const ObservationBatch scan = SweepScan(map, 1, i, 40);
    ASSERT_TRUE(store->Write(scan).ok());
    ASSERT_TRUE(reference->Write(scan).ok());
    ASSERT_TRUE(all_float->Write(scan).ok());
    if (i == 170) {  // a restart once the dynamic states are wide
      EXPECT_GT(store->Stats().totals.wide_states, 0u);
      store.reset();
      store = OpenOrDie(map, dir.path(), options);
    }
  }
  const MapStats stats = reference->Stats();
  EXPECT_GT(stats.totals.dynamic_states, 0u);
  EXPECT_EQ(stats.totals.wide_states, stats.totals.dynamic_states);  // each has ~600 observations
  EXPECT_EQ(all_float->Stats().totals.wide_states, 0u);
  // At ~600 observations float is still accurate: the double fold must agree with it closely.
  for (uint32_t x = 0; x < 4; ++x) {
    for (uint32_t y = 0; y < 4; ++y) {
      const uint64_t key = map.grid.keys().Key(x, y, 0);
      const auto wide = reference->Snapshot(key), narrow = all_float->Snapshot(key);
      ASSERT_TRUE(wide.has_value() && narrow.has_value());
      if (wide->is_static) continue;
      const model::CompactSpectrum& a = wide->model->spectrum();
      const model::CompactSpectrum& b = narrow->model->spectrum();
      ASSERT_EQ(a.header(), b.header());
      for (size_t r = 0; r < a.periods() * model::kRealsPerPeriod; ++r) {
        EXPECT_NEAR(a.body()[r], b.body()[r], 1e-6) << key << " real " << r;
      }
    }
  }
  // The restarted store folded on from its checkpointed double bodies: the same bits.
  ExpectSameModels(*store, *reference, map);
}

// A move (docs/fleet.md, "Moving a map"): stopped writes are refused retryably with the move's
// message and everything submitted before is applied; a committed move outlives a reopen.
TEST(MapStoreTest, AMapThatMovesRefusesWritesRetryablyAndKeepsACommittedMove) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 1, 2);
  {
    auto store = OpenOrDie(map, dir.path());
    ASSERT_TRUE(store->Write(SweepScan(map, 1, 0, 100)).ok());
    EXPECT_TRUE(absl::IsFailedPrecondition(store->MarkMoved("b:1")));  // writes not stopped yet
    ASSERT_TRUE(store->StopWrites().ok());
    EXPECT_EQ(store->Move().state, MoveState::kWritesStopped);
    EXPECT_EQ(store->Stats().totals.observations, 100u);
    const absl::Status refused = store->Write(SweepScan(map, 2, 0, 100)).status();
    EXPECT_TRUE(absl::IsUnavailable(refused)) << refused;
    EXPECT_EQ(refused.message(), "map m is moving to another daemon; retry");
    EXPECT_TRUE(absl::IsUnavailable(store->PublishModels().status()));
    EXPECT_EQ(store->Predict(std::vector<uint64_t>{0}, std::vector<double>{1}, {}).size(), 1u);  // reads go on
    ASSERT_TRUE(store->ResumeWrites().ok());
    ASSERT_TRUE(store->Write(SweepScan(map, 2, 0, 100)).ok());
    ASSERT_TRUE(store->StopWrites().ok());
    ASSERT_TRUE(store->MarkMoved("b:1").ok());
    EXPECT_TRUE(store->MarkMoved("c:1").ok());  // idempotent: the first target stays
    EXPECT_TRUE(absl::IsFailedPrecondition(store->ResumeWrites()));
  }
  auto reopened = OpenOrDie(map, dir.path());
  EXPECT_EQ(reopened->Move().state, MoveState::kMoved);
  EXPECT_EQ(reopened->Move().moved_to, "b:1");
  EXPECT_TRUE(absl::IsUnavailable(reopened->Write(SweepScan(map, 3, 0, 100)).status()));
  EXPECT_EQ(reopened->Stats().totals.observations, 200u);
}

}  // namespace
}  // namespace fremen::storage
