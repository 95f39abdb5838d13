// Prequential per-order error counters and order selection (docs/model.md, "Order selection").
//
// Every observation, before it is folded into the spectrum, is scored against the published model
// at each order 0..L. The sums decay exponentially with a half-life (default 7 days) relative to the
// newest observation time, so that a quiet day does not erase a week of evidence; half-life 0 keeps
// plain sums, reset at each publication (the paper's "only since the last update"). Sums are
// double: a week of 1 Hz observations outgrows float's integers. Thread-safety: none.
#pragma once

#include <cstdint>
#include <vector>

#include "storage/model/order_selection.h"

namespace fremen::model {

enum class ErrorCriterion : uint8_t {
  kThreshold = 0,  // |[p > 0.5] − s|: the share of wrong binary estimates
  kSquared = 1,    // (p − s)²
};

class OrderErrors {
 public:
  explicit OrderErrors(int max_order = 5) : errors_(max_order + 1, 0.0) {}

  int max_order() const { return static_cast<int>(errors_.size()) - 1; }
  // Scores one observation s at time t, given the unclamped predictions at orders 0..L.
  void Add(double t, const double* predictions, float s, ErrorCriterion criterion, double half_life);
  // The order `rule` picks from the decayed error rates (order_selection.h).
  int BestOrder(const OrderRule& rule) const {
    return SelectOrder(errors_.data(), weight_, max_order(), rule);
  }
  // The decayed error rate of order l (error per decayed observation); 0 before any observation.
  double ErrorRate(int order) const { return weight_ > 0 ? errors_[order] / weight_ : 0.0; }
  double weight() const { return weight_; }
  double reference_time() const { return t_ref_; }
  const std::vector<double>& errors() const { return errors_; }
  void Reset();

  // For decoders.
  void Restore(double t_ref, double weight, std::vector<double> errors) {
    t_ref_ = t_ref;
    weight_ = weight;
    errors_ = std::move(errors);
  }
  bool operator==(const OrderErrors&) const = default;

 private:
  double t_ref_ = 0;   // the time the sums are decayed to (the newest scored observation)
  double weight_ = 0;  // decayed count of scored observations
  std::vector<double> errors_;
};

}  // namespace fremen::model
