// MapStore::PlanBoxSeries and PredictBoxSeries: a box at many times, its constant cells once and
// its varying cells per time, must be PredictBox at each time bit for bit.
#include <gtest/gtest.h>

#include <bit>
#include <cstring>

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

// The box at t as the series gives it: constant cells from the plan, varying ones predicted at t.
std::vector<float> Assemble(const MapStore& store, const BoxSeries& plan, double t) {
  std::vector<float> frame = plan.constant, varying;
  store.PredictBoxSeries(plan, {&t, 1}, varying);
  EXPECT_EQ(varying.size(), plan.varying.size());
  for (size_t i = 0; i < plan.varying.size(); ++i) frame[plan.varying[i]] = varying[i];
  return frame;
}

// Bit for bit (a float == would take -0 for 0).
void ExpectSameBits(const std::vector<float>& a, const std::vector<float>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(std::bit_cast<uint32_t>(a[i]), std::bit_cast<uint32_t>(b[i])) << what << ", cell " << i;
  }
}

// How many cells of a plan vary, for each option set, on a map with unobserved, never changed,
// published and not yet published states; each plan checked against PredictBox at several times.
struct Counts {
  size_t cells = 0, default_varying = 0, persistence_varying = 0, order0_varying = 0, order1_varying = 0;
};

Counts CheckEveryOption(const MapStore& store, const CellBox& box) {
  Counts counts;
  counts.cells = box.cell_count();
  const double t0 = 1.7e9 + 230 * 600.0;
  const double times[] = {t0, t0 + 900, t0 + 3 * 3600 + 7, t0 + 86400 * 2.5, t0 - 86400 * 30};
  struct Case {
    PredictOptions options;
    size_t* varying;
  };
  const Case cases[] = {{{false, -1}, &counts.default_varying},
                        {{true, -1}, &counts.persistence_varying},
                        {{false, 0}, &counts.order0_varying},
                        {{false, 1}, &counts.order1_varying}};
  for (const Case& c : cases) {
    const std::string what = absl::StrCat("persistence ", c.options.persistence, " order ", c.options.order);
    auto plan = store.PlanBoxSeries(box, times[0], c.options);
    EXPECT_TRUE(plan.ok()) << plan.status();
    if (!plan.ok()) return counts;
    *c.varying = plan->varying.size();
    EXPECT_EQ(plan->varying.size(), plan->varying_keys.size());
    EXPECT_TRUE(std::is_sorted(plan->varying.begin(), plan->varying.end())) << what;
    for (const double t : times) {
      std::vector<float> region;
      EXPECT_TRUE(store.PredictBox(box, t, c.options, region).ok());
      ExpectSameBits(Assemble(store, *plan, t), region, absl::StrCat(what, " at ", t));
    }
    // All the times in one call: time g's values are the g-th run of the output, each as alone.
    std::vector<float> together;
    store.PredictBoxSeries(*plan, times, together);
    const size_t n = plan->varying.size();
    EXPECT_EQ(together.size(), std::size(times) * n) << what;
    if (together.size() != std::size(times) * n) continue;
    for (size_t g = 0; g < std::size(times); ++g) {
      std::vector<float> alone;
      store.PredictBoxSeries(*plan, {&times[g], 1}, alone);
      ExpectSameBits(std::vector<float>(together.begin() + g * n, together.begin() + (g + 1) * n), alone,
                     absl::StrCat(what, ", time ", g, " of ", std::size(times), " in one call"));
    }
  }
  return counts;
}

class MapStoreSeriesTest : public ::testing::Test {
 protected:
  // Cells with x % 7 == 0 change daily, the rest stay free; the last scans are not yet published.
  void Fill(const MapInfo& map, size_t cells_per_scan) {
    store_ = OpenOrDie(map, dir_.path());
    // The first publication is at order 0 (no order scored yet); the second picks orders.
    for (uint64_t i = 0; i < 200; ++i) {
      ASSERT_TRUE(store_->Write(SweepScan(map, 1, i, cells_per_scan)).ok());
      if (i % 100 == 99) {
        ASSERT_TRUE(store_->PublishModels().ok());
      }
    }
    for (uint64_t i = 200; i < 230; ++i) ASSERT_TRUE(store_->Write(SweepScan(map, 1, i, cells_per_scan)).ok());
  }

  TempDir dir_;
  std::unique_ptr<MapStore> store_;
};

TEST_F(MapStoreSeriesTest, EqualsPredictBoxAtEveryTimeAndOnlyTheDynamicCellsVary) {
  const MapInfo map = GridMap("m", 40, 24, 3, 3);
  Fill(map, 300);
  const Counts counts = CheckEveryOption(*store_, {{3, 2, 0}, {37, 23, 3}});
  // Only the x % 7 == 0 columns change; their published models have orders > 0 (a daily wave).
  EXPECT_GT(counts.default_varying, 0u);
  EXPECT_LT(counts.default_varying, counts.cells / 7 + 1);
  // Persistence makes every changed state vary, including those not yet published or at order 0.
  EXPECT_GE(counts.persistence_varying, counts.default_varying);
  // At order 0 every model is its mean α0: nothing varies.
  EXPECT_EQ(counts.order0_varying, 0u);
  // At order 1 every published model varies, also those whose selected order is 0.
  EXPECT_GE(counts.order1_varying, counts.default_varying);
}

// From 2^16 cells the plan, and from 2^16 varying cells the predictions, run on the shards'
// threads: two whole-grid patches, all occupied then all free, make every cell change, and so vary
// under persistence.
TEST_F(MapStoreSeriesTest, ALargeBoxSpreadOverTheShardsToo) {
  const MapInfo map = GridMap("m", 300, 300, 1, 3);
  Fill(map, 2000);
  for (uint64_t i = 230; i < 232; ++i) {
    ObservationBatch whole;
    whole.writer_id = 1;
    whole.sequence = i + 1;
    whole.time = 1.7e9 + 600.0 * static_cast<double>(i);
    whole.patch.size = {300, 300, 1};
    whole.patch.values.assign(300 * 300, i % 2 ? 0.0f : 1.0f);
    ASSERT_TRUE(store_->Write(std::move(whole)).ok());
  }
  const Counts counts = CheckEveryOption(*store_, {{0, 0, 0}, {300, 300, 1}});
  EXPECT_GT(counts.default_varying, 100u);
  EXPECT_EQ(counts.persistence_varying, counts.cells);
  EXPECT_EQ(counts.order0_varying, 0u);
}

TEST_F(MapStoreSeriesTest, BadBoxesAreRefusedAsByPredictBox) {
  const MapInfo map = GridMap("m", 40, 20, 1, 2);
  Fill(map, 100);
  EXPECT_TRUE(absl::IsOutOfRange(store_->PlanBoxSeries({{0, 0, 0}, {41, 1, 1}}, 0, {}).status()));
  EXPECT_TRUE(absl::IsOutOfRange(store_->PlanBoxSeries({{5, 0, 0}, {5, 1, 1}}, 0, {}).status()));
}

}  // namespace
}  // namespace fremen::storage
