// The update job's storage side (docs/update-job.md): a publication updates only the states observed since
// their last one (and that survives checkpoints and restarts), runs a slice at a time while batches
// keep being applied and acknowledged and readers see the old or the new model of each state, and
// the interleaved result equals the recovery's replay of the log. Also run under the
// thread-sanitizer build (FREMEN_SANITIZE=thread).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <thread>

#include "storage/map_store.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/record_codec.h"
#include "storage/testing/open_map_store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using testing::GridMap;
using testing::OpenOrDie;
using fremen::testing::TempDir;

constexpr double kT0 = 1.7e9;

// Every cell of z-planes [z0, z1) (rows y < `rows` of them) at time t: value 1 where (x + y + i) is
// even, else 0, so that two scans make every cell dynamic.
ObservationBatch Planes(const MapInfo& map, uint64_t writer, uint64_t i, uint32_t z0, uint32_t z1, double t,
                        uint32_t rows = UINT32_MAX) {
  ObservationBatch b;
  b.writer_id = writer;
  b.sequence = i + 1;
  b.time = t;
  for (uint32_t z = z0; z < z1; ++z) {
    for (uint32_t y = 0; y < std::min(rows, map.grid.size[1]); ++y) {
      for (uint32_t x = 0; x < map.grid.size[0]; ++x) {
        b.keys.push_back(map.grid.keys().Key(x, y, z));
        b.values.push_back((x + y + i) % 2 == 0 ? 1.0f : 0.0f);
      }
    }
  }
  return b;
}

uint64_t Published(MapStore& store) {
  auto published = store.PublishModels();
  EXPECT_TRUE(published.ok()) << published.status();
  return published.ok() ? *published : UINT64_MAX;
}

// Every state's P and counters, encoded, in key order.
std::vector<std::string> Models(const MapStore& store, const MapInfo& map) {
  std::vector<std::string> out;
  for (uint32_t z = 0; z < map.grid.size[2]; ++z) {
    for (uint32_t y = 0; y < map.grid.size[1]; ++y) {
      for (uint32_t x = 0; x < map.grid.size[0]; ++x) {
        const auto s = store.Snapshot(map.grid.keys().Key(x, y, z));
        if (!s || s->is_static) {
          out.emplace_back();
          continue;
        }
        std::string m = model::EncodeStateModel(*s->model);
        if (s->lossless) m += s->lossless->Encode();
        out.push_back(std::move(m));
      }
    }
  }
  return out;
}

TEST(MapStoreUpdateTest, PublishesOnlyStatesObservedSinceTheirLastPublication) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 4, 2);
  auto store = OpenOrDie(map, dir.path());
  for (uint64_t i = 0; i < 3; ++i) ASSERT_TRUE(store->Write(Planes(map, 1, i, 0, 4, kT0 + 3600.0 * i)).ok());
  EXPECT_EQ(Published(*store), 16u * 16 * 4);
  const std::vector<std::string> after_first = Models(*store, map);
  EXPECT_EQ(Published(*store), 0u) << "nothing observed since: nothing to publish";
  EXPECT_EQ(Models(*store, map), after_first) << "a second run changed a model";
  // New observations of one plane: only its states are published again.
  ASSERT_TRUE(store->Write(Planes(map, 1, 3, 2, 3, kT0 + 3 * 3600.0)).ok());
  EXPECT_EQ(Published(*store), 16u * 16);
  EXPECT_EQ(Published(*store), 0u);
}

TEST(MapStoreUpdateTest, TouchedStatesSurviveCheckpointsAndRestarts) {
  TempDir dir;
  const MapInfo map = GridMap("m", 16, 16, 4, 2);
  {
    auto store = OpenOrDie(map, dir.path());
    for (uint64_t i = 0; i < 3; ++i) ASSERT_TRUE(store->Write(Planes(map, 1, i, 0, 4, kT0 + 3600.0 * i)).ok());
    ASSERT_TRUE(store->Checkpoint().ok());
  }
  {
    auto store = OpenOrDie(map, dir.path());
    EXPECT_EQ(Published(*store), 16u * 16 * 4) << "observed before the restart, not yet published";
    ASSERT_TRUE(store->Write(Planes(map, 1, 3, 1, 2, kT0 + 3 * 3600.0)).ok());
  }  // Close checkpoints
  {
    auto store = OpenOrDie(map, dir.path());
    EXPECT_EQ(Published(*store), 16u * 16) << "only the plane observed after the publication";
  }
  // The publication itself survives through the log: a crash image after it publishes nothing.
  TempDir image;
  {
    StoreOptions no_checkpoint;
    no_checkpoint.checkpoint_log_bytes = UINT64_MAX;
    auto store = OpenOrDie(map, dir.path(), no_checkpoint);
    ASSERT_TRUE(store->Write(Planes(map, 1, 4, 0, 1, kT0 + 4 * 3600.0)).ok());
    EXPECT_EQ(Published(*store), 16u * 16);
    std::filesystem::copy(dir.path(), image.path(), std::filesystem::copy_options::recursive |
                                                        std::filesystem::copy_options::overwrite_existing);
  }
  auto recovered = OpenOrDie(map, image.path());
  EXPECT_EQ(Published(*recovered), 0u);
}

// Ingest and queries during a publication: batches are acknowledged while it runs, a reader sees
// each state's old or new prediction and never anything else, and the interleaved result equals
// the recovery's replay of the log (where the publication is one record among the batches). The
// publication waits for a batch before its first slice (StoreOptions::publication_waits_for_a_batch),
// so that a batch is acknowledged during it however long a slice takes against a log sync.
TEST(MapStoreUpdateTest, IngestAndQueriesContinueDuringAPublicationThatEqualsItsReplay) {
  TempDir dir, image;
#if defined(__SANITIZE_THREAD__)
  constexpr uint32_t kNz = 1;  // the thread sanitizer's ~10x slowdown makes 65,536 states many slices
#else
  constexpr uint32_t kNz = 8;  // 524,288 dynamic states: many slices
#endif
  const MapInfo map = GridMap("m", 256, 256, kNz, 2);
  StoreOptions options;
  options.checkpoint_log_bytes = UINT64_MAX;  // the log holds everything, so a copy is a crash image to replay
  options.publication_waits_for_a_batch = true;
  auto store = OpenOrDie(map, dir.path(), options);
  for (uint64_t i = 0; i < 3; ++i) ASSERT_TRUE(store->Write(Planes(map, 1, i, 0, kNz, kT0 + 3600.0 * i)).ok());

  // The reader's cells (rows y ≥ 128) get no new observations, so each has exactly two possible
  // predictions: before the publication (γ0, nothing published yet) and after it.
  const double t = kT0 + 5 * 3600.0;
  std::vector<uint64_t> watched;
  for (uint32_t z = 0; z < kNz; ++z) {
    for (uint32_t y = 128; y < 256; y += 3) {
      for (uint32_t x = 0; x < 256; x += 5) watched.push_back(map.grid.keys().Key(x, y, z));
    }
  }
  const std::vector<float> before = store->Predict(watched, {&t, 1}, {});

  // The publication's progress and every acknowledgement are called on the map's applier thread,
  // one after another: an acknowledgement between the first progress call (0 done) and the last
  // (all done) came while the publication ran.
  std::atomic<bool> publication_started = false, publication_finished = false;
  const auto progress = [&](uint64_t done, uint64_t total) {
    publication_started = true;
    if (done == total) publication_finished = true;
  };
  std::atomic<bool> publishing = true;
  std::atomic<uint64_t> acked = 0, acked_during = 0, torn = 0, reads = 0;
  absl::Status write_failure;  // the writer's error, read once it has been joined
  std::atomic<bool> write_failed = false;
  std::thread writer([&] {
    // Rows y < 128 keep being observed; they include states the publication has not reached yet.
    for (uint64_t i = 3; publishing; ++i) {
      std::promise<absl::StatusOr<BatchAck>> answer;
      const absl::Status submitted =
          store->Submit(Planes(map, 2, i, 0, kNz, kT0 + 3600.0 * i, 128), [&](absl::StatusOr<BatchAck> ack) {
            if (ack.ok() && publication_started && !publication_finished) ++acked_during;
            answer.set_value(std::move(ack));
          });
      const absl::StatusOr<BatchAck> ack = submitted.ok() ? answer.get_future().get() : submitted;
      if (!ack.ok() || !ack->error.ok()) {
        write_failure = ack.ok() ? ack->error : ack.status();
        write_failed = true;
        // A held publication waits for a batch that will not come now: closing finishes it.
        (void)store->Close();
        break;
      }
      ++acked;
    }
  });
  std::vector<std::vector<float>> seen;
  std::thread reader([&] {
    while (publishing) {
      seen.push_back(store->Predict(watched, {&t, 1}, {}));
      ++reads;
    }
  });
  // Both are under way before the publication starts (a loaded machine may be slow to start a
  // thread or to sync the log's first batch), so that the reads below cover the publication.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  while ((acked == 0 || reads == 0) && !write_failed && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const bool under_way = acked > 0 && reads > 0;
  auto published =
      under_way && !write_failed ? store->PublishModels(progress) : absl::StatusOr<uint64_t>(absl::AbortedError("not run"));
  publishing = false;
  writer.join();
  reader.join();
  ASSERT_TRUE(write_failure.ok()) << write_failure;
  ASSERT_TRUE(under_way) << "the writer or the reader did not start within 2 minutes";
  ASSERT_TRUE(published.ok()) << published.status();
  EXPECT_EQ(*published, 256u * 256 * kNz);
  EXPECT_TRUE(publication_finished);
  const std::vector<float> after = store->Predict(watched, {&t, 1}, {});
  for (const std::vector<float>& read : seen) {
    for (size_t j = 0; j < watched.size(); ++j) {
      if (read[j] != before[j] && read[j] != after[j]) ++torn;
    }
  }
  EXPECT_EQ(torn, 0u) << "a reader saw a prediction that is neither the old nor the new one";
  EXPECT_GT(reads, 0u);
  EXPECT_GT(acked_during, 0u) << "no batch was acknowledged while the publication ran";

  std::filesystem::copy(dir.path(), image.path(), std::filesystem::copy_options::recursive |
                                                      std::filesystem::copy_options::overwrite_existing);
  auto replayed = OpenOrDie(map, image.path(), options);
  EXPECT_TRUE(Models(*replayed, map) == Models(*store, map)) << "the replay differs from the live publication";
}

TEST(MapStoreUpdateTest, LosslessPublicationUpdatesTheHistoryAndKeepsItExact) {
  TempDir dir;
  MapInfo map = GridMap("m", 8, 8, 1, 2);
  map.lossless_sampling_period = 600;
  map.lossless_origin = kT0;
  auto store = OpenOrDie(map, dir.path());
  // Four days of 10-min samples: cells with x even follow a daily square wave, the rest flip daily.
  const int kSlots = 4 * 144;
  for (int i = 0; i < kSlots; ++i) {
    ObservationBatch b;
    b.writer_id = 1;
    b.sequence = i + 1;
    b.time = kT0 + 600.0 * i;
    for (uint32_t y = 0; y < 8; ++y) {
      for (uint32_t x = 0; x < 8; ++x) {
        const bool day = (i % 144) >= 72;
        const bool value = x % 2 == 0 ? day : ((i / 144) % 2 == 0) != (y % 2 == 0);
        b.keys.push_back(map.grid.keys().Key(x, y, 0));
        b.values.push_back(value ? 1.0f : 0.0f);
      }
    }
    ASSERT_TRUE(store->Write(std::move(b)).ok());
  }
  EXPECT_EQ(Published(*store), 64u);
  for (uint32_t x = 0; x < 8; ++x) {
    const auto s = store->Snapshot(map.grid.keys().Key(x, 3, 0));
    ASSERT_TRUE(s && s->lossless);
    EXPECT_EQ(s->lossless->update_slot(), static_cast<uint64_t>(kSlots)) << "the history was not updated";
    EXPECT_GT(s->lossless->model().order(), 0) << "x = " << x;
    auto past = s->lossless->Reconstruct(0, kSlots);
    ASSERT_TRUE(past.ok());
    for (int i = 0; i < kSlots; ++i) {
      const bool day = (i % 144) >= 72;
      const bool value = x % 2 == 0 ? day : ((i / 144) % 2 == 0) != (3 % 2 == 0);
      ASSERT_EQ((*past)[i], value ? model::SlotState::kOccupied : model::SlotState::kFree) << x << " slot " << i;
    }
  }
  if (auto daily = store->Snapshot(map.grid.keys().Key(0, 0, 0)); daily && daily->lossless) {
    EXPECT_LT(daily->lossless->EstimationError().rate(), 0.05) << "a square wave needs few outliers";
  }
  const auto first = Models(*store, map);
  EXPECT_EQ(Published(*store), 0u);
  EXPECT_EQ(Models(*store, map), first);
}

}  // namespace
}  // namespace fremen::storage
