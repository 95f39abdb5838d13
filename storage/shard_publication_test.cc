// Shard's publication slices (shard_publication.cc): incremental states are published a fixed
// number at a time under the shard's exclusive lock, so that readers wait for one chunk at most;
// and a region read between two slices answers with the models of that moment.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "storage/model/kernels/region_predict.h"
#include "storage/shard.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

// One shard of a 50×60 grid (3000 cells) in a temporary directory, and its keys.
class ShardPublicationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(settings_.ok()) << settings_.status();
    auto shard = Shard::Open(info_, *settings_, dir_.path() + "/shard-0", LmdbOptions{});
    ASSERT_TRUE(shard.ok()) << shard.status();
    shard_ = *std::move(shard);
    for (uint32_t y = 0; y < 60; ++y) {
      for (uint32_t x = 0; x < 50; ++x) keys_.push_back(info_.grid.keys().Key(x, y, 0));
    }
  }

  fremen::testing::TempDir dir_;
  const MapInfo info_ = testing::GridMap("slices", 50, 60, 1, 1);
  const absl::StatusOr<model::ModelSettings> settings_ = ModelSettingsOf(info_);
  std::unique_ptr<Shard> shard_;
  std::vector<uint64_t> keys_;
};

TEST_F(ShardPublicationTest, PublishesIncrementalStatesInChunksOf1024PerLock) {
  // Two scans of opposite values make every cell dynamic and touched.
  for (int i = 0; i < 2; ++i) {
    const std::vector<float> values(keys_.size(), static_cast<float>(i));
    shard_->Apply(ScanContext(settings_->periods, 1.7e9 + 600.0 * i), keys_, values);
  }
  ASSERT_EQ(shard_->BeginPublication(), 3000u);
  // A zero budget ends each call after its first chunk.
  EXPECT_FALSE(shard_->ContinuePublication(std::chrono::nanoseconds(0)));
  EXPECT_EQ(shard_->publication_done(), 1024u);
  EXPECT_FALSE(shard_->ContinuePublication(std::chrono::nanoseconds(0)));
  EXPECT_EQ(shard_->publication_done(), 2048u);
  EXPECT_TRUE(shard_->ContinuePublication(std::chrono::nanoseconds(0)));
  EXPECT_EQ(shard_->publication_done(), 3000u);
}

// A region of the shard's cells, each as the point prediction, as floats and as bytes.
void ExpectRegionEqualsPoints(const Shard& shard, const MapInfo& info, const model::PhasorTable& table) {
  const CellBox box{{0, 0, 0}, {50, 60, 1}};
  std::vector<float> region(box.cell_count(), 7.0f);
  std::vector<uint8_t> bytes(box.cell_count(), 77);
  shard.PredictBox(box, table, {}, region.data(), nullptr);
  shard.PredictBox(box, table, {}, bytes.data(), nullptr);
  for (uint32_t y = 0, i = 0; y < 60; ++y) {
    for (uint32_t x = 0; x < 50; ++x, ++i) {
      const float p = shard.Predict(info.grid.keys().Key(x, y, 0), table, {});
      ASSERT_EQ(region[i], p) << x << "," << y;
      ASSERT_EQ(bytes[i], model::QuantizeProbability(p)) << x << "," << y;
    }
  }
}

// Regions read the shard's models brick by brick from a copy made at the first region after a
// change (storage/brick_models.h). Between the slices of a publication that changes every model,
// and after it, a region must give each cell's point prediction.
TEST_F(ShardPublicationTest, RegionsBetweenSlicesAnswerTheModelsOfTheMoment) {
  // Three days of hourly scans: each cell high for part of the day (its phase from x), then the
  // three more days with the pattern reversed, which changes every model.
  const auto scans = [&](double first_day, bool reversed) {
    for (int h = 0; h < 72; ++h) {
      const double t = 1.7e9 + 86400.0 * first_day + 3600.0 * h;
      std::vector<float> values;
      for (const uint64_t key : keys_) {
        const uint32_t x = info_.grid.keys().Cell(key)[0];
        values.push_back(((h + x) % 24 < 10) != reversed ? 1.0f : 0.0f);
      }
      shard_->Apply(ScanContext(settings_->periods, t), keys_, values);
    }
  };
  scans(0, false);
  shard_->PublishAll();
  const model::PhasorTable table(settings_->periods, 1.7e9 + 86400.0 * 3 + 5000.0);
  ExpectRegionEqualsPoints(*shard_, info_, table);
  scans(3, true);
  ASSERT_EQ(shard_->BeginPublication(), 3000u);
  for (bool done = false; !done;) {
    done = shard_->ContinuePublication(std::chrono::nanoseconds(0));  // 1024 states a slice
    ExpectRegionEqualsPoints(*shard_, info_, table);
  }
}

}  // namespace
}  // namespace fremen::storage
