#include "storage/model/kernels/region_predict.h"

#include <algorithm>
#include <array>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// PredictColumns' AVX-512 and AVX2 paths, chosen at run time (x86-64 with GCC or Clang).
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define FREMEN_COLUMNS_PERMUTE 1
#else
#define FREMEN_COLUMNS_PERMUTE 0
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

// raw[i] += a[i]·cos ω_k[i] t − b[i]·sin ω_k[i] t, i < n: one component of a run of models.
void AddComponent(const uint16_t* k, const float* a, const float* b, size_t n, const float* cos_t,
                  const float* sin_t, float* raw) {
  for (size_t i = 0; i < n; ++i) raw[i] += a[i] * cos_t[k[i]] - b[i] * sin_t[k[i]];
}

// raw[i] = the sum of model at + i's first `terms` components, i < n: alpha0, then each component
// added in order, as SumBlock adds them.
void SumColumns(const ModelColumns& columns, size_t at, size_t n, int terms, const float* cos_t, const float* sin_t,
                float* raw) {
  // alpha0 + the first component in one pass, which is p = alpha0; p += term: the copy of alpha0
  // alone was a `rep movsq`, whose start-up cost a brick's run of ~60 models does not amortise
  // (a fifth of the kernel's samples).
  const float* alpha0 = columns.alpha0() + at;
  if (terms == 0) {
    for (size_t i = 0; i < n; ++i) raw[i] = alpha0[i];
    return;
  }
  const uint16_t* k = columns.k(0) + at;
  const float *a = columns.a(0) + at, *b = columns.b(0) + at;
  for (size_t i = 0; i < n; ++i) raw[i] = alpha0[i] + (a[i] * cos_t[k[i]] - b[i] * sin_t[k[i]]);
  for (int j = 1; j < terms; ++j) {
    AddComponent(columns.k(j) + at, columns.a(j) + at, columns.b(j) + at, n, cos_t, sin_t, raw);
  }
}

#if FREMEN_COLUMNS_PERMUTE
// The same sums several models at a time, with the cosines and sines of their periods looked up by
// vector permutes: the float tables of Ω (at most 32 periods, zero-padded to whole vectors:
// PhasorTable::cos_f) are held in registers. g++ 12 builds AddComponent's vectors from eight scalar
// loads each, and AVX2's gathers were slower than those loads on this machine's AMD EPYC
// (docs/performance.md, "A brick's models in one run"). Multiplications, subtraction and additions
// as separate IEEE operations in SumColumns' order, no FMA: each sum is SumColumns' to the bit
// (this file is compiled with -ffp-contract=off, so no build fuses them). Each vector is then
// clamped (maxps and minps, as Clamp) and written out, quantised as QuantizeProbability (p · 255 +
// 0.5 as two IEEE operations, then truncated). A run's last, partial vector reads past it
// (ModelColumns::kReadablePast) and keeps only its first lanes.
constexpr size_t kMostPermutedPeriods = 32;
static_assert(ModelColumns::kReadablePast >= 15 && PhasorTable::kFloatLanes % 16 == 0);

// GCC 12's avx512fintrin.h starts several intrinsics' results from _mm512_undefined_*(), which
// -Wmaybe-uninitialized reports at each use once they are inlined here (clang has no such warning).
#if !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

// AVX-512: sixteen models at a time. The table is one vector of sixteen (Ω of up to 16 periods,
// vpermps) or two (up to 32, vpermt2ps): one instruction a lookup.
template <int kParts>
[[gnu::target("avx512f"), gnu::always_inline]] inline __m512 LookUp16(const __m512* table, __m512i idx) {
  if constexpr (kParts == 1) return _mm512_permutexvar_ps(idx, table[0]);
  return _mm512_permutex2var_ps(table[0], idx, table[1]);
}
[[gnu::target("avx512f"), gnu::always_inline]] inline void Store16(__m512 p, __mmask16 lanes, float* out) {
  _mm512_mask_storeu_ps(out, lanes, p);
}
[[gnu::target("avx512f"), gnu::always_inline]] inline void Store16(__m512 p, __mmask16 lanes, uint8_t* out) {
  const __m512i q = _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(p, _mm512_set1_ps(255.0f)), _mm512_set1_ps(0.5f)));
  _mm512_mask_cvtusepi32_storeu_epi8(out, lanes, q);
}

template <int kParts, typename Out>
[[gnu::target("avx512f")]] void PredictColumns16(const ModelColumns& columns, size_t at, size_t n, int terms,
                                                 const float* cos_t, const float* sin_t, Out* out) {
  __m512 cos_v[kParts], sin_v[kParts];
  for (int part = 0; part < kParts; ++part) {
    cos_v[part] = _mm512_loadu_ps(cos_t + 16 * part);
    sin_v[part] = _mm512_loadu_ps(sin_t + 16 * part);
  }
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
  for (size_t i = 0; i < n; i += 16) {
    __m512 p = _mm512_loadu_ps(columns.alpha0() + at + i);
    for (int j = 0; j < terms; ++j) {
      const __m512i idx =
          _mm512_cvtepu16_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(columns.k(j) + at + i)));
      const __m512 term =
          _mm512_sub_ps(_mm512_mul_ps(_mm512_loadu_ps(columns.a(j) + at + i), LookUp16<kParts>(cos_v, idx)),
                        _mm512_mul_ps(_mm512_loadu_ps(columns.b(j) + at + i), LookUp16<kParts>(sin_v, idx)));
      p = _mm512_add_ps(p, term);
    }
    const __mmask16 lanes = n - i >= 16 ? 0xffff : static_cast<__mmask16>((1u << (n - i)) - 1);
    Store16(_mm512_min_ps(one, _mm512_max_ps(zero, p)), lanes, out + i);
  }
}

#if !defined(__clang__)
#pragma GCC diagnostic pop
#endif

// AVX2: eight models at a time. vpermps picks from a vector of eight by the index's low three bits;
// blends on bits 3 and 4 pick the vector: 3 permutes and 2 blends a lookup for the default 24
// periods. `bit3`, `bit4`: the index shifted so that those bits are the sign bits, which blendv reads.
template <int kParts>
[[gnu::target("avx2"), gnu::always_inline]] inline __m256 LookUp8(const __m256* table, __m256i idx, __m256 bit3,
                                                                  __m256 bit4) {
  const __m256 low = _mm256_permutevar8x32_ps(table[0], idx);
  if constexpr (kParts == 1) return low;
  const __m256 first16 = _mm256_blendv_ps(low, _mm256_permutevar8x32_ps(table[1], idx), bit3);
  if constexpr (kParts == 2) return first16;
  __m256 next16 = _mm256_permutevar8x32_ps(table[2], idx);
  if constexpr (kParts == 4) next16 = _mm256_blendv_ps(next16, _mm256_permutevar8x32_ps(table[3], idx), bit3);
  return _mm256_blendv_ps(first16, next16, bit4);
}
[[gnu::target("avx2"), gnu::always_inline]] inline void Store8(__m256 p, float* out) { _mm256_storeu_ps(out, p); }
[[gnu::target("avx2"), gnu::always_inline]] inline void Store8(__m256 p, uint8_t* out) {
  const __m256i q = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(p, _mm256_set1_ps(255.0f)), _mm256_set1_ps(0.5f)));
  const __m128i words = _mm_packus_epi32(_mm256_castsi256_si128(q), _mm256_extracti128_si256(q, 1));
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out), _mm_packus_epi16(words, words));
}

template <int kParts, typename Out>
[[gnu::target("avx2")]] void PredictColumns8(const ModelColumns& columns, size_t at, size_t n, int terms,
                                             const float* cos_t, const float* sin_t, Out* out) {
  __m256 cos_v[kParts], sin_v[kParts];
  for (int part = 0; part < kParts; ++part) {
    cos_v[part] = _mm256_loadu_ps(cos_t + 8 * part);
    sin_v[part] = _mm256_loadu_ps(sin_t + 8 * part);
  }
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  for (size_t i = 0; i < n; i += 8) {
    __m256 p = _mm256_loadu_ps(columns.alpha0() + at + i);
    for (int j = 0; j < terms; ++j) {
      const __m256i idx =
          _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(columns.k(j) + at + i)));
      const __m256 bit3 = _mm256_castsi256_ps(_mm256_slli_epi32(idx, 28));
      const __m256 bit4 = _mm256_castsi256_ps(_mm256_slli_epi32(idx, 27));
      const __m256 term = _mm256_sub_ps(
          _mm256_mul_ps(_mm256_loadu_ps(columns.a(j) + at + i), LookUp8<kParts>(cos_v, idx, bit3, bit4)),
          _mm256_mul_ps(_mm256_loadu_ps(columns.b(j) + at + i), LookUp8<kParts>(sin_v, idx, bit3, bit4)));
      p = _mm256_add_ps(p, term);
    }
    p = _mm256_min_ps(one, _mm256_max_ps(zero, p));
    if (i + 8 <= n) {
      Store8(p, out + i);
    } else {
      Out last[8];
      Store8(p, last);
      std::copy_n(last, n - i, out + i);
    }
  }
}

const bool kHasAvx512 = __builtin_cpu_supports("avx512f");
const bool kHasAvx2 = __builtin_cpu_supports("avx2");
#endif

bool Can(ColumnsPath path, size_t periods) {
#if FREMEN_COLUMNS_PERMUTE
  if (path == ColumnsPath::kAvx512) return kHasAvx512 && periods <= kMostPermutedPeriods;
  if (path == ColumnsPath::kAvx2) return kHasAvx2 && periods <= kMostPermutedPeriods;
#endif
  return path == ColumnsPath::kScalar;
}

ColumnsPath PathFor(size_t periods) {
  for (const ColumnsPath path : {ColumnsPath::kAvx512, ColumnsPath::kAvx2}) {
    if (Can(path, periods)) return path;
  }
  return ColumnsPath::kScalar;
}

// PredictColumns on `path`; kScalar: a block of models at a time, summed, then clamped (and
// quantised) together.
template <typename Out>
void ColumnsRange(ColumnsPath path, const ModelColumns& columns, size_t first, size_t count, int terms,
                  const PhasorTable& phasors, Out* out) {
  const float *cos_t = phasors.cos_f(), *sin_t = phasors.sin_f();
#if FREMEN_COLUMNS_PERMUTE
  const bool wide = phasors.size() > 16, wider = phasors.size() > 24;
  if (path == ColumnsPath::kAvx512) {
    return wide ? PredictColumns16<2>(columns, first, count, terms, cos_t, sin_t, out)
                : PredictColumns16<1>(columns, first, count, terms, cos_t, sin_t, out);
  }
  if (path == ColumnsPath::kAvx2) {
    if (phasors.size() <= 8) return PredictColumns8<1>(columns, first, count, terms, cos_t, sin_t, out);
    if (!wide) return PredictColumns8<2>(columns, first, count, terms, cos_t, sin_t, out);
    return wider ? PredictColumns8<4>(columns, first, count, terms, cos_t, sin_t, out)
                 : PredictColumns8<3>(columns, first, count, terms, cos_t, sin_t, out);
  }
#endif
  (void)path;
  float raw[kBlock];
  for (size_t start = 0; start < count; start += kBlock) {
    const size_t n = std::min(kBlock, count - start);
    SumColumns(columns, first + start, n, terms, cos_t, sin_t, raw);
    Emit(raw, n, out + start);
  }
}

}  // namespace

void PredictColumns(const ModelColumns& columns, size_t first, size_t count, int terms, const PhasorTable& phasors,
                    float* out) {
  ColumnsRange(PathFor(phasors.size()), columns, first, count, terms, phasors, out);
}

void PredictColumnsU8(const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, uint8_t* out) {
  ColumnsRange(PathFor(phasors.size()), columns, first, count, terms, phasors, out);
}

ColumnsPath PredictColumnsPath(size_t periods) { return PathFor(periods); }

bool PredictColumnsCan(ColumnsPath path, size_t periods) { return Can(path, periods); }

void PredictColumnsOn(ColumnsPath path, const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, float* out) {
  ColumnsRange(path, columns, first, count, terms, phasors, out);
}

void PredictColumnsOn(ColumnsPath path, const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, uint8_t* out) {
  ColumnsRange(path, columns, first, count, terms, phasors, out);
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
