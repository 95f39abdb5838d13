// CompactModels: the published models P (docs/model.md, "Published model P") of many states in a
// flat array of fixed-stride records, what region queries and prequential scoring read.
//
// Record for max order L (stride 8 + 2·L' + 8·L bytes, L' = L rounded up to even; 60 B at L = 5):
//   CompactModelHeader {float alpha0; uint8 order; uint8 published; uint16 count}  8 B
//   uint16 k[L']   period indices (padded so that the floats stay 4-byte aligned)
//   float  a[L]    α cos φ   (α cos(ωt + φ) = a·cos ωt − b·sin ωt: no trigonometry per state)
//   float  b[L]    α sin φ
// Components past `count` are zero (k = 0, a = b = 0), so a kernel may evaluate any order up to L
// without comparing it to count: the extra terms add exactly zero. That is PublishedModel::Predict's
// "an order above the components held uses all of them".
//
// A state without P (published = 0) predicts alpha0 (its γ0) at every order and is not
// scored. New records are unpublished with alpha0 = 0.5 (γ0 of an empty spectrum).
// Thread-safety: none; one writer, or many readers of an unchanging table.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "storage/model/published_model.h"
#include "storage/model/kernels/record_buffer.h"

namespace fremen::model {

struct CompactModelHeader {
  float alpha0 = 0.5f;
  uint8_t order = 0;
  uint8_t published = 0;
  uint16_t count = 0;
};
static_assert(sizeof(CompactModelHeader) == 8);

class CompactModels {
 public:
  static constexpr size_t StrideFor(int max_order) {
    const size_t l = static_cast<size_t>(max_order);
    return sizeof(CompactModelHeader) + KBytes(l) + 2 * l * sizeof(float);
  }

  // REQUIRES: 0 <= max_order <= kMaxMaxOrder.
  explicit CompactModels(int max_order, size_t size = 0);

  int max_order() const { return max_order_; }
  size_t size() const { return buffer_.size(); }
  size_t stride() const { return buffer_.stride(); }
  size_t bytes() const { return buffer_.bytes(); }

  // Grows with unpublished records (alpha0 0.5) or shrinks to n records.
  void Resize(size_t n);

  // REQUIRES: model.components().size() <= max_order().
  void Set(size_t i, const PublishedModel& model);
  // A state with no P yet: predicts alpha0 (its γ0).
  void SetUnpublished(size_t i, float alpha0);
  // The components held by record i (its first header(i).count).
  std::vector<Component> Components(size_t i) const;
  // The model of record i as a value (MeanOnly(alpha0) when unpublished).
  PublishedModel Get(size_t i) const;
  // Whether record i holds exactly `model` (published, same α0, order and components).
  bool Holds(size_t i, const PublishedModel& model) const;
  // From a bit per record beside the records (kept with the header's flag by Resize, Set,
  // SetUnpublished and MarkPublished): a region tells a box's published states from the others
  // before it reads their records, and the records of a 1M-cell box do not fit in cache (a miss per
  // dynamic cell was 15% of a region's samples in Shard::PredictBox).
  bool published(size_t i) const { return (published_bits_[i / 64] >> (i % 64)) & 1u; }
  // Flags record i published (its header and bit), for a writer that fills its components itself
  // (Publisher). Atomic on the bit's word, so that writers of disjoint records may still run at once.
  void MarkPublished(size_t i) {
    header(i).published = 1;
    std::atomic_ref(published_bits_[i / 64]).fetch_or(uint64_t{1} << (i % 64), std::memory_order_relaxed);
  }

  // The unclamped predictions of record i at orders 0..L, in double, exactly as
  // PublishedModel::PredictAllOrders: what the prequential scoring compares with p > 0.5, where float
  // rounding could flip a verdict.
  void PredictAllOrders(size_t i, const PhasorTable& phasors, double* out) const {
    const CompactModelHeader& h = header(i);
    double p = h.alpha0;
    out[0] = p;
    for (int l = 1; l <= max_order_; ++l) {
      if (l <= h.count) p += a(i)[l - 1] * phasors.cos(k(i)[l - 1]) - b(i)[l - 1] * phasors.sin(k(i)[l - 1]);
      out[l] = p;
    }
  }

  // Raw access for the kernels.
  CompactModelHeader& header(size_t i) { return *reinterpret_cast<CompactModelHeader*>(buffer_.record(i)); }
  const CompactModelHeader& header(size_t i) const {
    return *reinterpret_cast<const CompactModelHeader*>(buffer_.record(i));
  }
  uint16_t* k(size_t i) { return reinterpret_cast<uint16_t*>(buffer_.record(i) + kKOffset); }
  const uint16_t* k(size_t i) const { return reinterpret_cast<const uint16_t*>(buffer_.record(i) + kKOffset); }
  float* a(size_t i) { return reinterpret_cast<float*>(buffer_.record(i) + a_offset_); }
  const float* a(size_t i) const { return reinterpret_cast<const float*>(buffer_.record(i) + a_offset_); }
  float* b(size_t i) { return reinterpret_cast<float*>(buffer_.record(i) + b_offset_); }
  const float* b(size_t i) const { return reinterpret_cast<const float*>(buffer_.record(i) + b_offset_); }
  const std::byte* record(size_t i) const { return buffer_.record(i); }
  size_t a_offset() const { return a_offset_; }
  size_t b_offset() const { return b_offset_; }
  static constexpr size_t kKOffset = sizeof(CompactModelHeader);

 private:
  static constexpr size_t KBytes(size_t l) { return (l + 1) / 2 * 2 * sizeof(uint16_t); }
  // Zero components and an unpublished header with `alpha0`.
  void Clear(size_t i, float alpha0);

  int max_order_;
  size_t a_offset_;
  size_t b_offset_;
  RecordBuffer buffer_;
  std::vector<uint64_t> published_bits_;  // bit i: header(i).published; bits past size() are 0
};

}  // namespace fremen::model
