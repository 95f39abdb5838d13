#include "storage/model/kernels/scan_update.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "storage/model/model_settings.h"
#include "storage/model/state_model.h"

namespace fremen::model {
namespace {

// One scan: a time and (cell, value) pairs, cells in random order with repeats.
struct Scan {
  double t;
  std::vector<uint32_t> cells;
  std::vector<float> values;
};

std::vector<Scan> RandomScans(size_t count, size_t cells, double t0, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Scan> scans(count);
  double t = t0;
  for (Scan& scan : scans) {
    t += 3600 * u(rng);
    scan.t = t;
    const size_t n = 1 + static_cast<size_t>(u(rng) * cells);
    for (size_t i = 0; i < n; ++i) {
      scan.cells.push_back(static_cast<uint32_t>(u(rng) * cells));
      // Mostly hard values with a daily rhythm, some soft ones.
      const double p = 0.5 + 0.4 * std::cos(ReducedPhase(t, 86400) + scan.cells.back());
      scan.values.push_back(u(rng) < 0.1 ? static_cast<float>(u(rng)) : (u(rng) < p ? 1.0f : 0.0f));
    }
  }
  return scans;
}

void ExpectSameSpectrum(const RecordArena& arena, size_t i, const CompactSpectrum& spectrum) {
  EXPECT_EQ(arena.header(i), spectrum.header()) << "cell " << i;
  EXPECT_EQ(std::memcmp(arena.body(i), spectrum.body(), spectrum.periods() * kRealsPerPeriod * sizeof(float)), 0)
      << "cell " << i;
}

TEST(ScanUpdateTest, ValidateScanNamesTheOffendingElement) {
  const std::vector<uint32_t> cells = {0, 4, 2};
  EXPECT_TRUE(ValidateScan(5, cells, std::vector<float>{0, 1, 0.5f}).ok());
  EXPECT_EQ(ValidateScan(5, cells, std::vector<float>{0, 1}).code(), absl::StatusCode::kInvalidArgument);
  const absl::Status outside = ValidateScan(4, cells, std::vector<float>{0, 1, 0});
  EXPECT_EQ(outside.code(), absl::StatusCode::kOutOfRange);
  EXPECT_NE(outside.message().find("cells[1]"), std::string::npos);
  const absl::Status nan = ValidateScan(5, cells, std::vector<float>{0, NAN, 0});
  EXPECT_EQ(nan.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(nan.message().find("values[1]"), std::string::npos);
  EXPECT_FALSE(ValidateScan(5, cells, std::vector<float>{0, 1, 1.5f}).ok());
}

// Both kernels' paths: the default Ω (K = 24, unrolled) and any other K.
TEST(ScanUpdateTest, ApplyScanEqualsFoldObservationPerRecord) {
  for (const PeriodSet& periods : {PeriodSet::Default(), *PeriodSet::Harmonics(86400.0 * 30, 7)}) {
    constexpr size_t kCells = 500;
    RecordArena arena(periods.size(), kCells);
    std::vector<CompactSpectrum> reference(kCells, CompactSpectrum(periods.size()));
    for (const Scan& scan : RandomScans(60, kCells, 1.7e9, 1)) {
      const ScanPhasors<float> phasors(PhasorTable(periods, scan.t));
      ApplyScan(arena, phasors, scan.cells, scan.values);
      for (size_t i = 0; i < scan.cells.size(); ++i) reference[scan.cells[i]].Observe(phasors, scan.values[i]);
    }
    for (size_t i = 0; i < kCells; ++i) ExpectSameSpectrum(arena, i, reference[i]);
  }
}

TEST(ScanUpdateTest, ApplyDenseScanEqualsFoldObservationPerRecord) {
  for (const PeriodSet& periods : {PeriodSet::Default(), *PeriodSet::Harmonics(86400.0 * 30, 7)}) {
    constexpr size_t kCells = 100;
    RecordArena arena(periods.size(), kCells);
    std::vector<CompactSpectrum> reference(kCells, CompactSpectrum(periods.size()));
    std::mt19937_64 rng(2);
    for (int scan = 0; scan < 40; ++scan) {
      const ScanPhasors<float> phasors(PhasorTable(periods, 1.7e9 + 977.0 * scan));
      const size_t first = rng() % kCells;
      std::vector<float> values(rng() % (kCells - first + 1));
      for (float& v : values) v = static_cast<float>(rng() % 3) / 2;
      ApplyDenseScan(arena, phasors, first, values);
      for (size_t i = 0; i < values.size(); ++i) reference[first + i].Observe(phasors, values[i]);
    }
    for (size_t i = 0; i < kCells; ++i) ExpectSameSpectrum(arena, i, reference[i]);
  }
}

class ScoredScanTest : public ::testing::TestWithParam<double> {};

// The fused pass must equal the single-state model's Observe (score, then fold) in spectrum and error
// counters, for published and unpublished cells, across a republication.
TEST_P(ScoredScanTest, ScoreAndApplyScanEqualsStateModelObserve) {
  ModelSettings settings;
  settings.error_half_life = GetParam();
  const PeriodSet& periods = settings.periods;
  constexpr size_t kCells = 300;
  RecordArena arena(periods.size(), kCells);
  CompactModels models(settings.max_order, kCells);
  OrderErrorTable errors(settings.max_order, kCells);
  const ScanScoring scoring{&models, &errors, settings.criterion, settings.error_half_life};
  std::vector<CompactStateModel> reference(kCells, CompactStateModel(settings));

  const auto scans = RandomScans(150, kCells, 1.7e9, 3);
  for (size_t s = 0; s < scans.size(); ++s) {
    const Scan& scan = scans[s];
    const PhasorTable table(periods, scan.t);
    ScoreAndApplyScan(arena, scoring, table, ScanPhasors<float>(table), scan.cells, scan.values);
    for (size_t i = 0; i < scan.cells.size(); ++i) reference[scan.cells[i]].Observe(table, scan.values[i]);
    // Publish two thirds of the cells after 50 scans, all of them after 100.
    if (s == 50 || s == 100) {
      for (size_t i = 0; i < kCells; ++i) {
        if (s == 50 && i % 3 == 0) continue;
        reference[i].Update();
        models.Set(i, reference[i].published());
        if (settings.error_half_life == 0) errors.Reset(i);
      }
    }
  }
  int scored_orders = 0;
  for (size_t i = 0; i < kCells; ++i) {
    ExpectSameSpectrum(arena, i, reference[i].spectrum());
    EXPECT_EQ(errors.Get(i), reference[i].order_errors()) << "cell " << i;
    scored_orders += errors.BestOrder(i, settings.order_rule) > 0;
  }
  EXPECT_GT(scored_orders, 0);  // the test exercised more than order 0
}

INSTANTIATE_TEST_SUITE_P(HalfLives, ScoredScanTest, ::testing::Values(7 * 86400.0, 0.0));

TEST(ScanUpdateTest, ScoreScanThenApplyScanEqualsTheFusedPass) {
  ModelSettings settings;
  const PeriodSet& periods = settings.periods;
  constexpr size_t kCells = 200;
  RecordArena fused_arena(periods.size(), kCells), split_arena(periods.size(), kCells);
  CompactModels models(settings.max_order, kCells);
  OrderErrorTable fused_errors(settings.max_order, kCells), split_errors(settings.max_order, kCells);
  CompactStateModel warm(settings);
  for (int h = 0; h < 24 * 14; ++h) warm.Observe(1.7e9 + 3600.0 * h, h % 24 < 8 ? 1.0f : 0.0f);
  warm.Publish(3);
  for (size_t i = 0; i < kCells; i += 2) models.Set(i, warm.published());
  for (const Scan& scan : RandomScans(30, kCells, 1.7e9 + 14 * 86400.0, 4)) {
    const PhasorTable table(periods, scan.t);
    const ScanPhasors<float> phasors(table);
    ScoreAndApplyScan(fused_arena, {&models, &fused_errors, settings.criterion, settings.error_half_life}, table,
                      phasors, scan.cells, scan.values);
    ScoreScan({&models, &split_errors, settings.criterion, settings.error_half_life}, table, scan.cells, scan.values);
    ApplyScan(split_arena, phasors, scan.cells, scan.values);
  }
  for (size_t i = 0; i < kCells; ++i) {
    EXPECT_EQ(fused_errors.Get(i), split_errors.Get(i));
    EXPECT_EQ(fused_arena.header(i), split_arena.header(i));
  }
  EXPECT_GT(fused_errors.Get(0).weight(), 0);
  EXPECT_EQ(fused_errors.Get(1).weight(), 0);  // unpublished: not scored
}

}  // namespace
}  // namespace fremen::model
