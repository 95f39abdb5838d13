#include "server/convert/query_convert.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "storage/model/lossless/lossless_history.h"
#include "storage/model/state_model.h"

namespace fremen::server {
namespace {

storage::MapInfo Grid() {
  storage::MapInfo map;
  map.name = "lab";
  map.grid.size = {64, 64, 1};
  return map;
}

TEST(QueryConvertTest, NeverChangedStateIsSaidSo) {
  storage::StateSnapshot snapshot;
  snapshot.static_state.Observe(100, 1);
  snapshot.static_state.Observe(160, 1);
  const storage::MapInfo map = Grid();
  v1::StateModel out;
  StateModelToProto(map, model::ModelSettings(), map.grid.keys().Key(5, 9, 0), snapshot, true, out);
  EXPECT_TRUE(out.never_changed());
  EXPECT_EQ(out.cell().x(), 5u);
  EXPECT_EQ(out.cell().y(), 9u);
  EXPECT_EQ(out.observations(), 2u);
  EXPECT_EQ(out.first_time(), 100);
  EXPECT_EQ(out.last_time(), 160);
  EXPECT_EQ(out.mean(), 1);
  EXPECT_EQ(out.published_mean(), 1);
  EXPECT_EQ(out.spectrum_size(), 0);
  EXPECT_EQ(out.persistence().last_value(), 1);
  EXPECT_FALSE(out.has_lossless());
}

TEST(QueryConvertTest, DynamicStateHasSpectrumModelErrorsAndPersistence) {
  const model::ModelSettings settings;
  model::CompactStateModel m(settings);
  // A day/night square wave sampled hourly over two weeks.
  for (int h = 0; h < 24 * 14; ++h) m.Observe(3600.0 * h, (h % 24) >= 8 && (h % 24) < 20 ? 1.0f : 0.0f);
  m.Publish(2);
  storage::StateSnapshot snapshot;
  snapshot.is_static = false;
  snapshot.model = m;
  snapshot.name = "n";
  v1::StateModel out;
  StateModelToProto(Grid(), settings, 1, snapshot, true, out);
  EXPECT_FALSE(out.never_changed());
  EXPECT_EQ(out.name(), "n");
  EXPECT_EQ(out.observations(), 24u * 14);
  EXPECT_NEAR(out.mean(), 0.5, 1e-6);
  ASSERT_EQ(out.spectrum_size(), 24);
  EXPECT_NEAR(out.spectrum(0).period_seconds(), 604800, 1e-6);
  EXPECT_NEAR(out.spectrum(6).period_seconds(), 86400, 1e-6);
  EXPECT_NEAR(out.spectrum(6).amplitude(), 2 * std::abs(m.spectrum().gamma(6)), 1e-9);
  // The daily harmonic is the strongest component of P.
  EXPECT_EQ(out.selected_order(), 2u);
  ASSERT_GE(out.published_size(), 1);
  EXPECT_NEAR(out.published(0).period_seconds(), 86400, 1e-6);
  EXPECT_NEAR(out.published(0).amplitude(), m.published().components()[0].amplitude(), 1e-6);
  EXPECT_EQ(out.order_errors_size(), settings.max_order + 1);
  EXPECT_EQ(out.persistence().last_time(), 3600.0 * (24 * 14 - 1));
  EXPECT_GT(out.persistence().tau_seconds(), 0);

  out.Clear();
  StateModelToProto(Grid(), settings, 1, snapshot, false, out);
  EXPECT_EQ(out.spectrum_size(), 0);
  EXPECT_GE(out.published_size(), 1);
}

TEST(QueryConvertTest, LosslessHistoryAsIntervals) {
  auto history = model::LosslessHistory::Create(1000, 60);
  ASSERT_TRUE(history.ok());
  // Slots 0..9 and 20..29 observed; 5..7 and 25 occupied.
  for (int slot : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29}) {
    const bool occupied = (slot >= 5 && slot <= 7) || slot == 25;
    ASSERT_TRUE(history->Add(1000 + 60.0 * slot, occupied ? 1.0f : 0.0f).ok());
  }
  const model::ModelSettings settings;
  storage::StateSnapshot snapshot;
  snapshot.is_static = false;
  snapshot.model.emplace(settings);
  snapshot.lossless = *history;
  v1::StateModel out;
  StateModelToProto(Grid(), settings, 1, snapshot, false, out);
  const v1::LosslessModel& l = out.lossless();
  EXPECT_EQ(l.origin(), 1000);
  EXPECT_EQ(l.sampling_seconds(), 60);
  EXPECT_EQ(l.slot_count(), 30u);
  ASSERT_EQ(l.unobserved_size(), 1);
  EXPECT_EQ(l.unobserved(0).start(), 1000 + 600);
  EXPECT_EQ(l.unobserved(0).end(), 1000 + 1200);
  // Before any update P is 0 everywhere: the occupied runs are the outliers.
  ASSERT_EQ(l.outliers_size(), 2);
  EXPECT_EQ(l.outliers(0).start(), 1000 + 300);
  EXPECT_EQ(l.outliers(0).end(), 1000 + 480);
  EXPECT_EQ(l.outliers(1).start(), 1000 + 1500);
  EXPECT_EQ(l.outliers(1).end(), 1000 + 1560);
  EXPECT_NEAR(l.estimation_error(), 4.0 / 20, 1e-12);
  EXPECT_FALSE(l.truncated());
}

TEST(QueryConvertTest, MapStats) {
  storage::MapStats stats;
  stats.totals.states = 10;
  stats.totals.dynamic_states = 3;
  stats.totals.observations = 99;
  stats.totals.disk_bytes = 4096;
  stats.totals.memory_bytes = 2048;
  stats.totals.order_histogram = {1, 0, 2};
  stats.log_bytes = 77;
  stats.compression_ratio = 1.5;
  stats.mean_prediction_error = 0.25;
  stats.estimation_error = 0.01;
  stats.lossless_prediction_error = 0.02;
  v1::MapStats out;
  MapStatsToProto(stats, out);
  EXPECT_EQ(out.states(), 10u);
  EXPECT_EQ(out.dynamic_states(), 3u);
  EXPECT_EQ(out.observations(), 99u);
  EXPECT_EQ(out.disk_bytes(), 4096u);
  EXPECT_EQ(out.memory_bytes(), 2048u);
  EXPECT_THAT(out.order_histogram(), ::testing::ElementsAre(1u, 0u, 2u));
  EXPECT_EQ(out.log_bytes(), 77u);
  EXPECT_EQ(out.compression_ratio(), 1.5);
  EXPECT_EQ(out.mean_prediction_error(), 0.25);
  EXPECT_EQ(out.lossless_estimation_error(), 0.01);
  EXPECT_EQ(out.lossless_prediction_error(), 0.02);
  EXPECT_FALSE(out.has_last_update()) << "no update yet";

  stats.last_update = storage::UpdateRecord{1.7e9 + 0.5, 0.61, 3, 0.3, 0.2, {1, 0, 2}};
  MapStatsToProto(stats, out);
  ASSERT_TRUE(out.has_last_update());
  EXPECT_EQ(out.last_update().start_time().seconds(), 1'700'000'000);
  EXPECT_EQ(out.last_update().start_time().nanos(), 500'000'000);
  EXPECT_EQ(out.last_update().duration_seconds(), 0.61);
  EXPECT_EQ(out.last_update().states_updated(), 3u);
  EXPECT_EQ(out.last_update().prediction_error_before(), 0.3);
  EXPECT_EQ(out.last_update().prediction_error_after(), 0.2);
  EXPECT_THAT(out.last_update().order_histogram(), ::testing::ElementsAre(1u, 0u, 2u));
}

}  // namespace
}  // namespace fremen::server
