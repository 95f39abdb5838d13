#include "storage/model/kernels/region_predict.h"

#include <algorithm>
#include <array>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fremen::model {
namespace {

// Orders (and max orders) up to this get kernels with the loop over components fully unrolled.
constexpr int kUnrolledOrders = 8;
// Template argument for "a number of components known only at run time".
constexpr int kRuntime = -1;

// Cells per block: the raw sums of a block are clamped (and quantised) in a separate loop, which the
// compiler vectorises without branches. Clamping inside the per-cell loop compiles to a compare and
// branch that mispredicts whenever p leaves [0, 1] at random (measured 20-25% slower at l = 2).
constexpr size_t kBlock = 256;

inline float Clamp01f(float p) { return std::min(std::max(p, 0.0f), 1.0f); }
// out[i] = Clamp01f(raw[i]). g++ 12 compiles Clamp01f's loop to compares and blends (3.5
// instructions a cell); maxps(0, p) is (0 > p ? 0 : p) and minps(1, q) is (1 < q ? 1 : q), which
// are std::max(p, 0) and std::min(q, 1) to the bit, NaN and -0 included.
void Clamp(const float* raw, size_t n, float* out) {
  size_t i = 0;
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  for (; i + 4 <= n; i += 4) _mm_storeu_ps(out + i, _mm_min_ps(one, _mm_max_ps(zero, _mm_loadu_ps(raw + i))));
#endif
  for (; i < n; ++i) out[i] = Clamp01f(raw[i]);
}
void Emit(const float* raw, size_t n, float* out) { Clamp(raw, n, out); }
// Two loops (the clamp in place): g++ 12 vectorises neither half when clamp and conversion share one
// loop without AVX-512 ("control flow in loop": the comparisons and the conversion may trap), so the
// portable build's quantisation ran scalar where a native build's ran 16 wide.
void Emit(float* raw, size_t n, uint8_t* out) {
  Clamp(raw, n, raw);
  for (size_t i = 0; i < n; ++i) out[i] = QuantizeProbability(raw[i]);
}

// kOrderMask[order][j] = 1 if component j counts at that order, else 0: loaded from memory, so that the
// compiler cannot see the values and turn the masking back into branches on the order (as it does with
// `j < order ? term : 0` and with `term * float(j < order)`).
constexpr auto kOrderMask = [] {
  std::array<std::array<float, kUnrolledOrders>, kUnrolledOrders + 1> mask{};
  for (int order = 0; order <= kUnrolledOrders; ++order) {
    for (int j = 0; j < order; ++j) mask[order][j] = 1.0f;
  }
  return mask;
}();

// Where the records of a query lie: consecutive from `first` (a region of the table), or at the
// listed indices (a box of cells, whose states sit where they were first observed).
struct Consecutive {
  size_t first;
  size_t operator[](size_t i) const { return first + i; }
};
struct Listed {
  const uint32_t* records;
  size_t operator[](size_t i) const { return records[i]; }
};

// Where a record's fields are, for the loops below.
struct RecordLayout {
  const std::byte* base;
  size_t stride, a_offset, b_offset;
  const std::byte* operator()(size_t record) const { return base + record * stride; }
};

// raw[i] = the unclamped sum of the first kUsed components of record records[start + i], i < n; with
// kMasked, each record's components past its own order are multiplied by 0 (they add exactly zero,
// so the sum is that of its own order). By masking rather than by a loop bound, because a trip
// count that changes from cell to cell mispredicts a branch per cell (measured 2x slower with mixed
// orders).
template <int kUsed, bool kMasked, typename Records>
void SumBlock(const RecordLayout& layout, Records records, size_t start, size_t n, const float* cos_t,
              const float* sin_t, float* raw) {
  for (size_t i = 0; i < n; ++i) {
    const std::byte* r = layout(records[start + i]);
    const auto* h = reinterpret_cast<const CompactModelHeader*>(r);
    const auto* k = reinterpret_cast<const uint16_t*>(r + CompactModels::kKOffset);
    const auto* a = reinterpret_cast<const float*>(r + layout.a_offset);
    const auto* b = reinterpret_cast<const float*>(r + layout.b_offset);
    float p = h->alpha0;
    if constexpr (kMasked) {
      const float* mask = kOrderMask[std::min<int>(h->order, kUnrolledOrders)].data();
      for (int j = 0; j < kUsed; ++j) p += (a[j] * cos_t[k[j]] - b[j] * sin_t[k[j]]) * mask[j];
    } else {
      for (int j = 0; j < kUsed; ++j) p += a[j] * cos_t[k[j]] - b[j] * sin_t[k[j]];
    }
    raw[i] = p;
  }
}

// SumBlock<used, masked> for a block whose highest own order is `used` (<= kMax <= kUnrolledOrders);
// `masked` false when every record's order is `used` (a multiplication by 1 changes nothing).
template <int kMax, int kUsed = 0, typename Records>
void SumBlockUpTo(int used, bool masked, const RecordLayout& layout, Records records, size_t start, size_t n,
                  const float* cos_t, const float* sin_t, float* raw) {
  if constexpr (kUsed < kMax) {
    if (used != kUsed) {
      return SumBlockUpTo<kMax, kUsed + 1>(used, masked, layout, records, start, n, cos_t, sin_t, raw);
    }
  }
  if (masked) {
    SumBlock<kUsed, true>(layout, records, start, n, cos_t, sin_t, raw);
  } else {
    SumBlock<kUsed, false>(layout, records, start, n, cos_t, sin_t, raw);
  }
}

// kTerms components per record (kRuntime: `terms`). With kOwnOrder, kTerms is L and each record keeps
// only its first `order` terms; a block of records goes through the loop of its highest order, not
// L's: a map whose states all chose order 3 of L = 5 computes 3 terms a cell, not 5 with two masked
// (and without the mask when all the block's orders are the same).
// Finding that order reads each record's header first, which also starts every record's miss at
// once rather than one after another.
template <int kTerms, bool kOwnOrder, typename Records, typename Out>
void PredictRange(const CompactModels& models, Records records, size_t count, const float* cos_t, const float* sin_t,
                  int terms, Out* out) {
  const RecordLayout layout{count > 0 ? models.record(0) : nullptr, models.stride(), models.a_offset(),
                            models.b_offset()};
  float raw[kBlock];
  for (size_t start = 0; start < count; start += kBlock) {
    const size_t n = std::min(kBlock, count - start);
    if constexpr (kOwnOrder && kTerms != kRuntime) {
      int used = 0, lowest = kTerms;
      for (size_t i = 0; i < n; ++i) {
        const int order = reinterpret_cast<const CompactModelHeader*>(layout(records[start + i]))->order;
        used = std::max(used, order);
        lowest = std::min(lowest, order);
      }
      used = std::min(used, kTerms);
      SumBlockUpTo<kTerms>(used, /*masked=*/lowest < used, layout, records, start, n, cos_t, sin_t, raw);
    } else if constexpr (kTerms != kRuntime) {
      SumBlock<kTerms, false>(layout, records, start, n, cos_t, sin_t, raw);
    } else {
      for (size_t i = 0; i < n; ++i) {
        const std::byte* r = layout(records[start + i]);
        const auto* k = reinterpret_cast<const uint16_t*>(r + CompactModels::kKOffset);
        const auto* a = reinterpret_cast<const float*>(r + layout.a_offset);
        const auto* b = reinterpret_cast<const float*>(r + layout.b_offset);
        float p = reinterpret_cast<const CompactModelHeader*>(r)->alpha0;
        const int used = kOwnOrder ? reinterpret_cast<const CompactModelHeader*>(r)->order : terms;
        for (int j = 0; j < used; ++j) p += a[j] * cos_t[k[j]] - b[j] * sin_t[k[j]];
        raw[i] = p;
      }
    }
    Emit(raw, n, out + start);
  }
}

// PredictRange<terms, kOwnOrder>, unrolled when terms <= kUnrolledOrders.
template <bool kOwnOrder, int kTerms = 0, typename Records, typename Out>
void Dispatch(const CompactModels& models, Records records, size_t count, const PhasorTable& phasors, int terms,
              Out* out) {
  if constexpr (kTerms > kUnrolledOrders) {
    PredictRange<kRuntime, kOwnOrder>(models, records, count, phasors.cos_f(), phasors.sin_f(), terms, out);
  } else if (terms == kTerms) {
    PredictRange<kTerms, kOwnOrder>(models, records, count, phasors.cos_f(), phasors.sin_f(), terms, out);
  } else {
    Dispatch<kOwnOrder, kTerms + 1>(models, records, count, phasors, terms, out);
  }
}

template <typename Records, typename Out>
void Predict(const CompactModels& models, Records records, size_t count, const PhasorTable& phasors, int order,
             Out* out) {
  if (order < 0) return Dispatch<true>(models, records, count, phasors, models.max_order(), out);
  // Past L nothing is stored; past count the components are zero.
  Dispatch<false>(models, records, count, phasors, std::min(order, models.max_order()), out);
}

// raw[i] += a[i]·cos ω_k[i] t − b[i]·sin ω_k[i] t, i < n: one component of a run of models. (An AVX2
// version with two gathers per eight models was slower on this machine's AMD EPYC: 178-235M
// models/s against 245-295M, fremen_model_bench's BM_PredictColumnsU8 with 2^17 models;
// docs/performance.md, "A brick's models in one run".)
void AddComponent(const uint16_t* k, const float* a, const float* b, size_t n, const float* cos_t,
                  const float* sin_t, float* raw) {
  for (size_t i = 0; i < n; ++i) raw[i] += a[i] * cos_t[k[i]] - b[i] * sin_t[k[i]];
}

// PredictColumns: a block of models at a time, component by component over the block. Each model's
// sum is alpha0, then its components added in order, as SumBlock adds them.
template <typename Out>
void ColumnsRange(const ModelColumns& columns, size_t first, size_t count, int terms, const float* cos_t,
                  const float* sin_t, Out* out) {
  float raw[kBlock];
  for (size_t start = 0; start < count; start += kBlock) {
    const size_t n = std::min(kBlock, count - start), at = first + start;
    // alpha0 + the first component in one pass, which is p = alpha0; p += term: the copy of alpha0
    // alone was a `rep movsq`, whose start-up cost a brick's run of ~60 models does not amortise
    // (a fifth of the kernel's samples).
    const float* alpha0 = columns.alpha0() + at;
    if (terms == 0) {
      for (size_t i = 0; i < n; ++i) raw[i] = alpha0[i];
    } else {
      const uint16_t* k = columns.k(0) + at;
      const float *a = columns.a(0) + at, *b = columns.b(0) + at;
      for (size_t i = 0; i < n; ++i) raw[i] = alpha0[i] + (a[i] * cos_t[k[i]] - b[i] * sin_t[k[i]]);
    }
    for (int j = 1; j < terms; ++j) {
      AddComponent(columns.k(j) + at, columns.a(j) + at, columns.b(j) + at, n, cos_t, sin_t, raw);
    }
    Emit(raw, n, out + start);
  }
}

}  // namespace

void PredictColumns(const ModelColumns& columns, size_t first, size_t count, int terms, const PhasorTable& phasors,
                    float* out) {
  ColumnsRange(columns, first, count, terms, phasors.cos_f(), phasors.sin_f(), out);
}

void PredictColumnsU8(const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, uint8_t* out) {
  ColumnsRange(columns, first, count, terms, phasors.cos_f(), phasors.sin_f(), out);
}

void PredictRegion(const CompactModels& models, size_t first, size_t count, const PhasorTable& phasors, int order,
                   float* out) {
  Predict(models, Consecutive{first}, count, phasors, order, out);
}

void PredictRegionU8(const CompactModels& models, size_t first, size_t count, const PhasorTable& phasors, int order,
                     uint8_t* out) {
  Predict(models, Consecutive{first}, count, phasors, order, out);
}

void PredictRecords(const CompactModels& models, std::span<const uint32_t> records, const PhasorTable& phasors,
                    int order, float* out) {
  Predict(models, Listed{records.data()}, records.size(), phasors, order, out);
}

}  // namespace fremen::model
