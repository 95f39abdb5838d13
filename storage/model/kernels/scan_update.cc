#include "storage/model/kernels/scan_update.h"

#include <cassert>

#include "absl/strings/str_cat.h"
#include "storage/model/kernels/cpu_dispatch.h"
#include "storage/model/model_settings.h"

namespace fremen::model {
namespace {

// How many cells ahead the random-order kernels prefetch. A record is several cache lines, and the
// core tracks only a few dozen outstanding misses, so a short distance suffices (tuned with
// model_bench: 4-16 perform alike; 2 is too short to hide the DRAM latency).
constexpr size_t kPrefetchCells = 8;
// The same for a dense patch (2-8 perform alike).
constexpr size_t kDensePrefetchRecords = 4;

// FoldObservation with the period count known at compile time when kPeriods != 0. Its loop runs over
// 4K reals with K known only at run time; told K, the compiler unrolls it completely (measured 1.8x
// faster while the records are in cache, e.g. a robot re-scanning its surroundings). The same code,
// so the same rounding.
template <size_t kPeriods>
[[gnu::always_inline]] inline void FoldCell(RecordArena& arena, size_t cell, const ScanPhasors<float>& phasors,
                                            float s) {
  assert(cell < arena.size());
  if constexpr (kPeriods != 0) {
    if (phasors.periods() != kPeriods) __builtin_unreachable();
  }
  FoldObservation(arena.header(cell), arena.body(cell), phasors, s);
}

// Runs fold.template operator()<kPeriods>() with kPeriods = K for the default Ω, else 0 (any K).
template <typename Fold>
void WithPeriodCount(size_t periods, Fold fold) {
  if (periods == kDefaultPeriodCount) {
    fold.template operator()<kDefaultPeriodCount>();
  } else {
    fold.template operator()<0>();
  }
}

void ScoreCell(const ScanScoring& scoring, const PhasorTable& table, ScanDecay& decay, size_t cell, float s) {
  const CompactModels& models = *scoring.models;
  if (!models.published(cell)) return;  // as BasicStateModel::Score: nothing to score against yet
  double predictions[kMaxMaxOrder + 1];
  models.PredictAllOrders(cell, table, predictions);
  scoring.errors->Add(cell, predictions, s, scoring.criterion, decay);
}

// Runs per_cell(cell, value) over the scan, with `prefetch(cell)` issued kPrefetchCells ahead.
// Callers pass always-inline lambdas: see PrefetchLines on why prefetches must not sit in a call.
template <typename Prefetch, typename PerCell>
[[gnu::always_inline]] inline void ForEachCell(std::span<const uint32_t> cells, std::span<const float> values,
                                               Prefetch prefetch, PerCell per_cell) {
  assert(cells.size() == values.size());
  const size_t n = cells.size();
  for (size_t i = 0; i < n; ++i) {
    if (i + kPrefetchCells < n) prefetch(cells[i + kPrefetchCells]);
    per_cell(cells[i], values[i]);
  }
}

}  // namespace

absl::Status ValidateScan(size_t cell_count, std::span<const uint32_t> cells, std::span<const float> values) {
  if (cells.size() != values.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("cells and values must have equal lengths, got ", cells.size(), " and ", values.size()));
  }
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i] >= cell_count) {
      return absl::OutOfRangeError(
          absl::StrCat("cells[", i, "] = ", cells[i], " is outside the ", cell_count, " cells"));
    }
    if (!(values[i] >= 0.0f && values[i] <= 1.0f)) {
      return absl::InvalidArgumentError(absl::StrCat("values[", i, "] must be in [0, 1], got ", values[i]));
    }
  }
  return absl::OkStatus();
}

// The two update kernels are cloned for AVX2 (cpu_dispatch.h): the fold is 4K independent lanes.
FREMEN_KERNEL_CLONES void ApplyScan(RecordArena& arena, const ScanPhasors<float>& phasors,
                                    std::span<const uint32_t> cells, std::span<const float> values) {
  WithPeriodCount(phasors.periods(), [&]<size_t kPeriods>() {
    ForEachCell(
        cells, values,
        [&](size_t cell) __attribute__((always_inline)) { PrefetchForWrite(arena.record(cell), arena.stride()); },
        [&](size_t cell, float s) { FoldCell<kPeriods>(arena, cell, phasors, s); });
  });
}

FREMEN_KERNEL_CLONES void ApplyDenseScan(RecordArena& arena, const ScanPhasors<float>& phasors, size_t first,
                                         std::span<const float> values) {
  assert(first + values.size() <= arena.size());
  // The hardware prefetcher alone leaves the loop alternating between computing and waiting; an
  // explicit hint a few records ahead overlaps the two (measured 36M -> 48-52M records/s at K = 24).
  const size_t n = values.size();
  WithPeriodCount(phasors.periods(), [&]<size_t kPeriods>() {
    for (size_t i = 0; i < n; ++i) {
      if (i + kDensePrefetchRecords < n) {
        PrefetchForWrite(arena.record(first + i + kDensePrefetchRecords), arena.stride());
      }
      FoldCell<kPeriods>(arena, first + i, phasors, values[i]);
    }
  });
}

void ScoreScan(const ScanScoring& scoring, const PhasorTable& table, std::span<const uint32_t> cells,
               std::span<const float> values) {
  ScanDecay decay(table.time(), scoring.half_life);
  ForEachCell(
      cells, values,
      [&](size_t cell) __attribute__((always_inline)) {
        PrefetchForRead(scoring.models->record(cell), scoring.models->stride());
        PrefetchForWrite(scoring.errors->record(cell), scoring.errors->stride());
      },
      [&](size_t cell, float s) { ScoreCell(scoring, table, decay, cell, s); });
}

void ScoreAndApplyScan(RecordArena& arena, const ScanScoring& scoring, const PhasorTable& table,
                       const ScanPhasors<float>& phasors, std::span<const uint32_t> cells,
                       std::span<const float> values) {
  assert(table.time() == phasors.time());
  // Two passes, not one: scoring reads only P and the error counters, never the spectrum, so the
  // passes commute per cell; and each pass alone keeps fewer cache misses in flight per cell, which
  // is what limits random access (one fused pass measured 1.5x slower on unsorted cells, alike on
  // sorted ones).
  ScoreScan(scoring, table, cells, values);
  ApplyScan(arena, phasors, cells, values);
}

}  // namespace fremen::model
