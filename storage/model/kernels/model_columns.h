// ModelColumns: published models as columns (a structure of arrays), each at its own order, for
// the region kernel's runs over a brick's cells (PredictColumns, storage/brick_models.h).
//
// CompactModels keeps a model's fields together in one record, which suits reading one state; a
// run of many states through the same loop reads better as columns: alpha0 of every model in one
// array, then for each component j the period indices, a and b of every model in three. The loop
// over a run then goes component by component over consecutive models, whose sums are independent
// of each other, where the per-record loop summed a model's few components one after another, and
// read each record's header first to find the run's highest order.
//
// A model's components past its own order are stored as zero (k = 0, a = b = 0): they add exactly
// zero, so a run is computed at its highest own order without a per-model mask, and each model's
// sum is the one PredictRegion gives at its own order, bit for bit. (So the columns answer
// "each state's own order" only; a fixed order reads the records.)
// Thread-safety: none; one writer, then any number of readers of an unchanging table.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "storage/model/kernels/compact_models.h"

namespace fremen::model {

class ModelColumns {
 public:
  // REQUIRES: 0 <= max_order <= kMaxMaxOrder.
  explicit ModelColumns(int max_order);

  // Every column may be read this many entries past size(): a vector kernel loads whole vectors of
  // sixteen or eight at a run's end and drops the lanes past it, with no scalar tail (which was a
  // fifth of PredictColumns' time in runs of 60). After the last model they are zeros: period index 0.
  static constexpr size_t kReadablePast = 15;

  int max_order() const { return static_cast<int>(k_.size()); }
  size_t size() const { return order_.size(); }
  // Grows with zero models (alpha0 0, no components) or shrinks to n models.
  void Resize(size_t n);
  // Model i becomes record r of `models` at its own order.
  // REQUIRES: i < size(), model i is zero, models.max_order() == max_order().
  void SetZero(size_t i, const CompactModels& models, size_t r);

  const float* alpha0() const { return alpha0_.data(); }
  const uint8_t* order() const { return order_.data(); }
  // Component j (0-based) of every model, kReadablePast entries more. REQUIRES: j < max_order().
  const uint16_t* k(int j) const { return k_[j].data(); }
  const float* a(int j) const { return a_[j].data(); }
  const float* b(int j) const { return b_[j].data(); }
  size_t memory_bytes() const;

 private:
  std::vector<float> alpha0_;
  std::vector<uint8_t> order_;
  std::vector<std::vector<uint16_t>> k_;
  std::vector<std::vector<float>> a_, b_;
};

}  // namespace fremen::model
