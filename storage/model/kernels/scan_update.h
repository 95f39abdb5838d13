// The ingest kernels: one scan (one time t, many cells) folded into the working records of a map or
// shard, optionally scoring each cell's published model first (docs/model.md, "Spectrum" and "Order
// selection").
//
// Everything per scan is computed once (ScanPhasors: the phasors of t in double with range
// reduction, cast to float); per cell the update is FoldObservation — 4K float multiply-adds on one
// record, memory-bound. For a cell list in random order the kernel prefetches the records a few
// cells ahead so that their cache misses overlap; a caller that can sort the list (ids are usually
// sent sorted, delta-coded) gains further from page locality.
//
// The prequential scoring of the published models (order errors) is optional and separate: it reads
// only P and the error counters, never the spectrum, so ScoreAndApplyScan runs it as its own pass
// before the fold and the result equals scoring then folding each observation in turn.
// Thread-safety: none; the caller owns the arena and tables (one writer per shard).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "absl/status/status.h"
#include "storage/model/kernels/compact_models.h"
#include "storage/model/kernels/order_error_table.h"
#include "storage/model/phasor.h"
#include "storage/model/kernels/record_arena.h"
#include "storage/model/spectrum.h"

namespace fremen::model {

// The checked edge of the unchecked kernels below (bad input must get a precise status, not a crash):
// equal lengths, every cell < cell_count, every value in [0, 1]. Names the first offending element.
absl::Status ValidateScan(size_t cell_count, std::span<const uint32_t> cells, std::span<const float> values);

// Folds values[i] into the record of cells[i], in order (a cell listed twice is folded twice).
// REQUIRES: cells.size() == values.size(); every cell < arena.size(); values in [0, 1];
// phasors.periods() == arena.periods().
void ApplyScan(RecordArena& arena, const ScanPhasors<float>& phasors, std::span<const uint32_t> cells,
               std::span<const float> values);

// A dense patch: values[i] into the record of cell first + i.
// REQUIRES: first + values.size() <= arena.size(); as ApplyScan.
void ApplyDenseScan(RecordArena& arena, const ScanPhasors<float>& phasors, size_t first, std::span<const float> values);

// What the prequential scoring of a scan needs besides the cells: the published models, the error
// counters to update (same indexing as the arena) and the map's scoring settings.
struct ScanScoring {
  const CompactModels* models;
  OrderErrorTable* errors;
  ErrorCriterion criterion = ErrorCriterion::kThreshold;
  double half_life = 0;
};

// Scores values[i] against the published model of cells[i] at orders 0..L (unpublished cells are not
// scored), exactly as BasicStateModel::Observe does before folding. `table` is the double phasor
// table of the scan time. REQUIRES: models and errors of the same max order and size >= every cell.
void ScoreScan(const ScanScoring& scoring, const PhasorTable& table, std::span<const uint32_t> cells,
               std::span<const float> values);

// ScoreScan then ApplyScan per cell, in one pass over the cells. REQUIRES: phasors built from `table`.
void ScoreAndApplyScan(RecordArena& arena, const ScanScoring& scoring, const PhasorTable& table,
                       const ScanPhasors<float>& phasors, std::span<const uint32_t> cells,
                       std::span<const float> values);

}  // namespace fremen::model
