// OrderErrorTable: the prequential per-order error counters (OrderErrors; docs/model.md, "Order
// selection") of many states in a flat array of fixed-stride records, updated by the scan kernels in
// the same pass as the spectra.
//
// Record for max order L: double t_ref, weight, errors[L + 1] — (L + 3)·8 bytes, one 64-byte line at
// L = 5. Add() is OrderErrors::Add, operation for operation (the tests pin equality), on a record
// instead of a heap-backed object: a vector per state would cost an allocation and a pointer chase
// per scored cell.
//
// The decay factor 2^(−|t − t_ref|/half-life) is the one transcendental per scored observation. All
// cells of a scan share t, and the cells seen together in the previous scan share t_ref, so ScanDecay
// caches the last factor: a robot re-scanning an area pays one exp2 per scan, not per cell.
// Thread-safety: none; one writer, or many readers of an unchanging table.
#pragma once

#include <cmath>
#include <cstddef>

#include "storage/model/order_errors.h"
#include "storage/model/published_model.h"
#include "storage/model/kernels/record_buffer.h"

namespace fremen::model {

// The decay factors for observations at one time t.
class ScanDecay {
 public:
  ScanDecay(double t, double half_life) : t_(t), half_life_(half_life) {}
  double time() const { return t_; }
  double half_life() const { return half_life_; }
  // 2^(−|t − t_ref| / half-life): exactly OrderErrors' factor, whichever of t and t_ref is later
  // (floating subtraction is sign-symmetric).
  double Factor(double t_ref) {
    if (t_ref != cached_ref_) {
      cached_ref_ = t_ref;
      cached_factor_ = std::exp2(-std::fabs(t_ - t_ref) / half_life_);
    }
    return cached_factor_;
  }

 private:
  double t_, half_life_;
  double cached_ref_ = NAN, cached_factor_ = 1;
};

class OrderErrorTable {
 public:
  // The value of x, rounded as computed: keeps the compiler from fusing the product that makes x into
  // a following addition (an FMA). OrderErrors::Add cannot fuse `weight *= decay; weight += w` (its
  // weight might alias its error vector); fused here, the two would differ in the last bit.
  static double Unfused(double x) {
    asm("" : "+m"(x));
    return x;
  }

  static constexpr size_t StrideFor(int max_order) { return (static_cast<size_t>(max_order) + 3) * sizeof(double); }

  // REQUIRES: 0 <= max_order <= kMaxMaxOrder.
  explicit OrderErrorTable(int max_order, size_t size = 0) : max_order_(max_order), buffer_(StrideFor(max_order)) {
    buffer_.Resize(size);
  }

  int max_order() const { return max_order_; }
  size_t size() const { return buffer_.size(); }
  size_t stride() const { return buffer_.stride(); }
  size_t bytes() const { return buffer_.bytes(); }
  // Grows with empty records (no observation scored) or shrinks to n records.
  void Resize(size_t n) { buffer_.Resize(n); }

  // Scores one observation s at decay.time() on record i, given the unclamped predictions at
  // orders 0..L. The same as OrderErrors::Add(t, predictions, s, criterion, decay.half_life()).
  inline void Add(size_t i, const double* predictions, float s, ErrorCriterion criterion, ScanDecay& decay);

  // The order with the lowest decayed error rate, as OrderErrors::BestOrder.
  int BestOrder(size_t i, const OrderRule& rule) const;
  double ErrorRate(size_t i, int order) const {
    const double* r = rec(i);
    return r[kWeight] > 0 ? r[kErrors + order] / r[kWeight] : 0.0;
  }
  void Reset(size_t i);

  // Conversions to and from the single-state form.
  OrderErrors Get(size_t i) const;
  // REQUIRES: errors.max_order() == max_order().
  void Set(size_t i, const OrderErrors& errors);

  const std::byte* record(size_t i) const { return buffer_.record(i); }

 private:
  static constexpr size_t kTRef = 0, kWeight = 1, kErrors = 2;
  double* rec(size_t i) { return reinterpret_cast<double*>(buffer_.record(i)); }
  const double* rec(size_t i) const { return reinterpret_cast<const double*>(buffer_.record(i)); }

  int max_order_;
  RecordBuffer buffer_;
};

inline void OrderErrorTable::Add(size_t i, const double* predictions, float s, ErrorCriterion criterion,
                                 ScanDecay& decay) {
  double* r = rec(i);
  double& t_ref = r[kTRef];
  double& weight = r[kWeight];
  double* errors = r + kErrors;
  const double t = decay.time();
  double w = 1.0;
  if (decay.half_life() > 0) {
    if (weight == 0) t_ref = t;  // nothing to decay yet
    if (t > t_ref) {
      const double factor = decay.Factor(t_ref);
      for (int l = 0; l <= max_order_; ++l) errors[l] *= factor;
      weight = Unfused(weight * factor);
      t_ref = t;
    } else {
      w = decay.Factor(t_ref);  // an observation older than the newest enters already decayed
    }
  } else if (t > t_ref) {
    t_ref = t;
  }
  weight += w;
  for (int l = 0; l <= max_order_; ++l) {
    const double p = Clamp01(predictions[l]);
    const double e = criterion == ErrorCriterion::kThreshold ? std::fabs((p > 0.5 ? 1.0 : 0.0) - s) : (p - s) * (p - s);
    errors[l] += w * e;
  }
}

}  // namespace fremen::model
