// How a brick's cells get into a region: a box's row-major array of p, written by the shards
// (Shard::PredictBox).
//
// A brick's 512 handles are in Morton order; a box is row-major. Reading each cell's 4-byte handle
// and turning it into p was most of a 1M-cell region's time on a map of mostly never-changed cells
// (docs/performance.md). So each brick of a grid also keeps a BrickImage: its never-changed and
// unobserved cells as the bytes of the UINT8 output, row-major (x fastest), and a list of its
// dynamic cells. A region copies a brick's rows (32 bytes of a flat brick, 8 of a cubic one) and
// predicts the listed cells; it reads no handle. The image is kept by the shard as it sets each
// handle (Shard::SetHandle), so it is never stale: a cell only ever goes from unobserved to never
// changed to dynamic, and a dynamic index is its state's for the shard's life.
//
// The box's array holds p as float, or quantised as bytes (CellValue<uint8_t>, the UINT8 region
// output), so that a UINT8 region is written once, in its wire form, rather than as floats first.
// BoxBricks, beside it, numbers the bricks a box overlaps, so that the cells of bricks no shard
// holds are filled after the shards have written theirs.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "storage/cell_key.h"
#include "storage/model/kernels/region_predict.h"
#include "storage/queries.h"

namespace fremen::storage {

// p as a cell of a box of T: the float itself, or its byte round(255·p).
template <typename T>
T CellValue(float p);
template <>
inline float CellValue<float>(float p) { return p; }
template <>
inline uint8_t CellValue<uint8_t>(float p) { return model::QuantizeProbability(p); }

// The bricks a box overlaps, numbered as a grid of their own (x fastest): which of them some shard
// holds, so that a box's cells in no brick of any shard — and only those — are filled with the
// unobserved value (MapStoreImpl::PredictBox), not every cell first.
class BoxBricks {
 public:
  BoxBricks(const CellBox& box, const std::array<uint32_t, 3>& brick_size);

  size_t size() const { return size_t{count_[0]} * count_[1] * count_[2]; }
  // The number of brick (bx, by, bz) of the grid (in bricks), which the box overlaps.
  size_t Index(uint32_t bx, uint32_t by, uint32_t bz) const {
    return (size_t{bz - first_[2]} * count_[1] + (by - first_[1])) * count_[0] + (bx - first_[0]);
  }
  // Sets every cell of the box that lies in a brick i with held[i] == 0 to `value`; `out` is the
  // box's row-major array.
  template <typename T>
  void FillUnheld(const uint8_t* held, T value, T* out) const;

 private:
  CellBox box_;
  std::array<uint32_t, 3> brick_size_, first_, count_;
};

template <typename T>
void BoxBricks::FillUnheld(const uint8_t* held, T value, T* out) const {
  const uint64_t nx = box_.hi[0] - box_.lo[0], ny = box_.hi[1] - box_.lo[1];
  for (uint32_t bz = 0; bz < count_[2]; ++bz) {
    for (uint32_t by = 0; by < count_[1]; ++by) {
      const uint8_t* row_held = held + (size_t{bz} * count_[1] + by) * count_[0];
      if (std::find(row_held, row_held + count_[0], 0) == row_held + count_[0]) continue;
      const uint32_t y0 = std::max(box_.lo[1], (first_[1] + by) * brick_size_[1]);
      const uint32_t y1 = std::min(box_.hi[1], (first_[1] + by + 1) * brick_size_[1]);
      const uint32_t z0 = std::max(box_.lo[2], (first_[2] + bz) * brick_size_[2]);
      const uint32_t z1 = std::min(box_.hi[2], (first_[2] + bz + 1) * brick_size_[2]);
      for (uint32_t z = z0; z < z1; ++z) {
        for (uint32_t y = y0; y < y1; ++y) {
          T* row = out + ((z - box_.lo[2]) * ny + (y - box_.lo[1])) * nx - box_.lo[0];
          // Each run of unheld bricks along x in one fill (an empty map's box: a fill per row).
          for (uint32_t bx = 0; bx < count_[0];) {
            if (row_held[bx]) {
              ++bx;
              continue;
            }
            const uint32_t run = bx;
            while (bx < count_[0] && !row_held[bx]) ++bx;
            std::fill(row + std::max(box_.lo[0], (first_[0] + run) * brick_size_[0]),
                      row + std::min(box_.hi[0], (first_[0] + bx) * brick_size_[0]), value);
          }
        }
      }
    }
  }
}

// Where a brick's cells sit in its image: the row-major index (x fastest, then y, then z) of each
// Morton index, for the brick shape of one grid (32×16×1 or 8×8×8, sides powers of two).
class BrickLayout {
 public:
  explicit BrickLayout(const GridKeys& keys);

  const std::array<uint32_t, 3>& size() const { return size_; }
  uint32_t RowMajor(uint32_t local) const { return row_major_[local]; }
  // The axes of row-major index i.
  uint32_t X(uint32_t i) const { return i & (size_[0] - 1); }
  uint32_t Y(uint32_t i) const { return (i >> shift_y_) & (size_[1] - 1); }
  uint32_t Z(uint32_t i) const { return i >> shift_z_; }

 private:
  std::array<uint32_t, 3> size_;
  uint32_t shift_y_, shift_z_;
  std::array<uint16_t, 512> row_major_;
};

// One brick as a region query reads it. Value type.
class BrickImage {
 public:
  // Handles as the shard keeps them: kNoHandle (unobserved), kNeverChanged | value, or a dynamic
  // state's index (top bit clear).
  static constexpr uint32_t kNoHandle = UINT32_MAX;
  static constexpr uint32_t kNeverChanged = 0x80000000u;
  // A dynamic cell: its state's index and its row-major index in the brick.
  struct DynamicCell {
    uint32_t handle;
    uint32_t cell;
  };

  BrickImage() { bytes_.fill(kUnobservedByte); }

  // Cell i (row-major) now has `handle`. REQUIRES: a cell's handle goes only from kNoHandle to
  // never changed to dynamic (or straight to dynamic), and is set dynamic once.
  void Set(uint32_t i, uint32_t handle) {
    if (handle & kNeverChanged) {
      bytes_[i] = handle == kNoHandle ? kUnobservedByte : (handle & 1u) ? 255 : 0;
    } else {
      dynamic_.push_back({handle, i});
    }
  }

  // p of the cells [i, i + n) of one row, never-changed and unobserved ones exact (dynamic ones
  // are the caller's to overwrite), as T.
  template <typename T>
  void CopyRow(uint32_t i, uint32_t n, T* out) const;

  const std::vector<DynamicCell>& dynamic() const { return dynamic_; }
  const uint8_t* bytes() const { return bytes_.data(); }
  size_t memory_bytes() const { return sizeof(*this) + dynamic_.capacity() * sizeof(DynamicCell); }

 private:
  static constexpr uint8_t kUnobservedByte = 128;  // CellValue<uint8_t>(kUnobservedProbability)

  // A byte back to p: 0 → 0, 128 → 0.5, 255 → 1, exactly ((b + 1) >> 7 is 0, 1 or 2 halves).
  static float FloatOf(uint8_t b) { return static_cast<float>((b + 1) >> 7) * 0.5f; }

  std::array<uint8_t, 512> bytes_;
  std::vector<DynamicCell> dynamic_;  // in the order their states became dynamic
};

template <>
inline void BrickImage::CopyRow<uint8_t>(uint32_t i, uint32_t n, uint8_t* out) const {
  // A whole row of a flat or a cubic brick in a few moves, not a call.
  if (n == 32) {
    std::memcpy(out, bytes_.data() + i, 32);
  } else if (n == 8) {
    std::memcpy(out, bytes_.data() + i, 8);
  } else {
    std::memcpy(out, bytes_.data() + i, n);
  }
}

template <>
inline void BrickImage::CopyRow<float>(uint32_t i, uint32_t n, float* out) const {
  const uint8_t* in = bytes_.data() + i;
  uint32_t k = 0;
#if defined(__SSE2__)  // every x86-64: sixteen cells at a time
  const __m128i zero = _mm_setzero_si128(), one = _mm_set1_epi16(1);
  const __m128 half = _mm_set1_ps(0.5f);
  for (; k + 16 <= n; k += 16) {
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + k));
    const __m128i halves[2] = {_mm_srli_epi16(_mm_add_epi16(_mm_unpacklo_epi8(b, zero), one), 7),
                               _mm_srli_epi16(_mm_add_epi16(_mm_unpackhi_epi8(b, zero), one), 7)};
    for (int h = 0; h < 2; ++h) {
      _mm_storeu_ps(out + k + 8 * h, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(halves[h], zero)), half));
      _mm_storeu_ps(out + k + 8 * h + 4, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpackhi_epi16(halves[h], zero)), half));
    }
  }
#endif
  for (; k < n; ++k) out[k] = FloatOf(in[k]);
}

}  // namespace fremen::storage
