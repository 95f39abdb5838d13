// Publication, the update job's inner loop (docs/model.md, "Published model P" and "Order selection"):
// for each state choose the order with the lowest decayed prequential error, take the L strongest
// eligible components of its float spectrum and write its compact P. The result equals
// PublishedModel::FromSpectrum with OrderErrors::BestOrder's order, bit for bit (the tests pin it),
// without its per-state heap vectors and sort: γ_k is taken on the fly, the top L are kept by insertion
// into a small stack array, ranked by |γ|² (no square root) except in near-ties, where |γ| itself
// decides as in FromSpectrum.
//
// The job clears the error counters after publishing when the map's half-life is 0 (the paper's
// "only since the last update"); that is the caller's policy, not done here.
// Thread-safety: a Publisher is immutable; calls on disjoint output records may run concurrently.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "storage/model/kernels/compact_models.h"
#include "storage/model/kernels/order_error_table.h"
#include "storage/model/order_errors.h"
#include "storage/model/periods.h"
#include "storage/model/kernels/record_arena.h"
#include "storage/model/spectrum.h"

namespace fremen::model {

class Publisher {
 public:
  // REQUIRES: 0 <= max_order <= kMaxMaxOrder.
  Publisher(const PeriodSet& periods, int max_order);

  int max_order() const { return max_order_; }

  // P of `spectrum` at `order` into record `out` of `models`.
  // REQUIRES: 0 <= order <= max_order; models.max_order() == max_order(); spectrum of the Ω given.
  void Publish(const CompactSpectrum& spectrum, int order, CompactModels& models, size_t out) const;

  // Records [first, first + count) of `spectra` into the same records of `models`, each at the order
  // its error counters choose (BestOrder with `rule`).
  void PublishRange(const RecordArena& spectra, const OrderErrorTable& errors, size_t first, size_t count,
                    CompactModels& models, const OrderRule& rule) const;
  void PublishRange(const RecordArena& spectra, std::span<const OrderErrors> errors, size_t first, size_t count,
                    CompactModels& models, const OrderRule& rule) const;

 private:
  template <typename OrderOf>
  void PublishRecords(const RecordArena& spectra, size_t first, size_t count, CompactModels& models,
                      OrderOf order_of) const;

  int max_order_;
  std::vector<double> periods_;
};

// Every record of `spectra`. REQUIRES: errors and models at least as many records.
inline void PublishAll(const RecordArena& spectra, const OrderErrorTable& errors, const PeriodSet& periods,
                       CompactModels& models, const OrderRule& rule) {
  Publisher(periods, models.max_order()).PublishRange(spectra, errors, 0, spectra.size(), models, rule);
}
inline void PublishAll(const RecordArena& spectra, std::span<const OrderErrors> errors, const PeriodSet& periods,
                       CompactModels& models, const OrderRule& rule) {
  Publisher(periods, models.max_order()).PublishRange(spectra, errors, 0, spectra.size(), models, rule);
}

}  // namespace fremen::model
