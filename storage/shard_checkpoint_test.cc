// What a shard's checkpoint writes (Shard::PrepareCheckpoint / WriteCheckpoint) and what Load reads
// back: a dynamic state's published model has a record of its own (shard_records::kPublishedDb), so
// that the checkpoint after a publication writes only those; a dynamic record of data directory
// format 2, which holds its published model itself, is still read.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "storage/cell_key.h"
#include "storage/model/record_codec.h"
#include "storage/shard.h"
#include "storage/shard_records.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

namespace sr = shard_records;

std::span<const uint8_t> Bytes(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

class ShardCheckpointTest : public ::testing::Test {
 protected:
  ShardCheckpointTest() : info_(testing::GridMap("checkpoint", 20, 10, 1, 1)), settings_(*ModelSettingsOf(info_)) {
    for (uint32_t y = 0; y < 10; ++y) {
      for (uint32_t x = 0; x < 20; ++x) keys_.push_back(info_.grid.keys().Key(x, y, 0));
    }
    std::sort(keys_.begin(), keys_.end());
  }

  std::unique_ptr<Shard> Open() {
    auto shard = Shard::Open(info_, settings_, dir_.path() + "/shard-0", LmdbOptions{});
    EXPECT_TRUE(shard.ok()) << shard.status();
    return shard.ok() ? *std::move(shard) : nullptr;
  }

  // Scans every cell at `times` with alternating values: every cell becomes dynamic.
  void Observe(Shard& shard, std::initializer_list<double> times) {
    int i = 0;
    for (double t : times) {
      const std::vector<float> values(keys_.size(), static_cast<float>(i++ % 2));
      shard.Apply(ScanContext(settings_.periods, t), keys_, values);
    }
  }

  // Every state's whole model, encoded: what a reopened shard must give back byte for byte.
  std::vector<std::string> Models(const Shard& shard) const {
    std::vector<std::string> models;
    for (uint64_t key : keys_) {
      const auto snapshot = shard.Snapshot(key);
      models.push_back(snapshot && snapshot->model ? model::EncodeStateModel(*snapshot->model) : "");
    }
    return models;
  }

  // Reopens the shard (a restart): every state's model must read back byte for byte.
  void ExpectTheSameAfterReopening(std::unique_ptr<Shard>& shard) {
    const std::vector<std::string> before = Models(*shard);
    shard.reset();
    shard = Open();
    ASSERT_NE(shard, nullptr);
    EXPECT_EQ(Models(*shard), before);
  }

  // Changes the shard's files behind its back (a restart reads what f left): f gets the dynamic
  // and the published databases.
  static absl::Status Rewrite(Shard& shard, const std::function<absl::Status(LmdbTxn&, MDB_dbi, MDB_dbi)>& f) {
    return shard.env().Write([&](LmdbTxn& txn) -> absl::Status {
      auto dynamic = txn.Db(sr::kDynamicDb);
      auto published = txn.Db(sr::kPublishedDb);
      if (!dynamic.ok()) return dynamic.status();
      if (!published.ok()) return published.status();
      return f(txn, *dynamic, *published);
    });
  }

  // Every cell observed twice (dynamic), published and checkpointed at LSN 1.
  std::unique_ptr<Shard> PublishedAndCheckpointed() {
    auto shard = Open();
    Observe(*shard, {1.7e9, 1.7e9 + 600});
    shard->PublishAll();
    const absl::Status written = Checkpoint(*shard, 1);
    EXPECT_TRUE(written.ok()) << written;
    return written.ok() ? std::move(shard) : nullptr;
  }

  absl::Status Checkpoint(Shard& shard, uint64_t lsn) { return shard.WriteCheckpoint(shard.PrepareCheckpoint(lsn, {})); }

  MapInfo info_;
  model::ModelSettings settings_;
  std::vector<uint64_t> keys_;
  fremen::testing::TempDir dir_;
};

TEST_F(ShardCheckpointTest, AfterAPublicationOnlyThePublishedModelsAreWrittenAndReadBack) {
  auto shard = Open();
  Observe(*shard, {1.7e9, 1.7e9 + 600, 1.7e9 + 1200});
  const Shard::CheckpointImage observed = shard->PrepareCheckpoint(1, {});
  EXPECT_EQ(observed.dynamic.size(), keys_.size());
  EXPECT_TRUE(observed.published.empty());  // nothing published yet
  ASSERT_TRUE(shard->WriteCheckpoint(observed).ok());

  ASSERT_EQ(shard->PublishAll(), keys_.size());
  const Shard::CheckpointImage published = shard->PrepareCheckpoint(2, {});
  EXPECT_TRUE(published.dynamic.empty());
  EXPECT_TRUE(published.statics.empty());
  ASSERT_EQ(published.published.size(), keys_.size());
  for (const auto& [key, record] : published.published) {
    ASSERT_TRUE(model::DecodePublishedModel(record, settings_.periods.size(), settings_.max_order).ok()) << key;
  }
  ASSERT_TRUE(shard->WriteCheckpoint(published).ok());
  ASSERT_NE(Models(*shard)[0], "");
  ExpectTheSameAfterReopening(shard);
  EXPECT_EQ(shard->checkpoint_lsn(), 2u);
}

TEST_F(ShardCheckpointTest, AnObservedStateWritesItsDynamicRecordWithoutThePublishedModelAndThatRecordBeside) {
  auto shard = Open();
  Observe(*shard, {1.7e9, 1.7e9 + 600});
  shard->PublishAll();
  Observe(*shard, {1.7e9 + 1200});  // observed after its publication: every record changes
  const Shard::CheckpointImage image = shard->PrepareCheckpoint(1, {});
  ASSERT_EQ(image.dynamic.size(), keys_.size());
  ASSERT_EQ(image.published.size(), keys_.size());
  auto decoded = model::DecodeStateModel<float>(image.dynamic[0].second, settings_);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_FALSE(decoded->has_published());
  ASSERT_TRUE(shard->WriteCheckpoint(image).ok());
  ExpectTheSameAfterReopening(shard);
}

TEST_F(ShardCheckpointTest, AFormat2DynamicRecordHoldingItsPublishedModelIsRead) {
  auto shard = PublishedAndCheckpointed();
  ASSERT_NE(shard, nullptr);
  const std::vector<std::string> before = Models(*shard);
  // Rewritten as format 2 laid it out: each state's whole model in its dynamic record, no
  // published records.
  ASSERT_TRUE(Rewrite(*shard, [&](LmdbTxn& txn, MDB_dbi dynamic, MDB_dbi published) {
                for (size_t i = 0; i < keys_.size(); ++i) {
                  if (absl::Status s = txn.Put(dynamic, KeyBytes(keys_[i]), Bytes(before[i])); !s.ok()) return s;
                }
                return txn.Drop(published);
              }).ok());
  shard.reset();
  shard = Open();
  EXPECT_EQ(Models(*shard), before);
  // Its next checkpoint writes them in the layout of format 3 and reads back the same.
  shard->PublishAll();  // nothing touched: publishes nothing
  Observe(*shard, {1.7e9 + 1200});
  ASSERT_TRUE(Checkpoint(*shard, 2).ok());
  ExpectTheSameAfterReopening(shard);
}

TEST_F(ShardCheckpointTest, APublishedModelWithoutItsStateIsDataLoss) {
  auto shard = PublishedAndCheckpointed();
  ASSERT_NE(shard, nullptr);
  ASSERT_TRUE(Rewrite(*shard, [&](LmdbTxn& txn, MDB_dbi dynamic, MDB_dbi) {
                return txn.Delete(dynamic, KeyBytes(keys_[3]));
              }).ok());
  shard.reset();
  auto reopened = Shard::Open(info_, settings_, dir_.path() + "/shard-0", LmdbOptions{});
  ASSERT_TRUE(absl::IsDataLoss(reopened.status())) << reopened.status();
  EXPECT_NE(reopened.status().message().find("a published model without its state"), absl::string_view::npos)
      << reopened.status();
}

}  // namespace
}  // namespace fremen::storage
