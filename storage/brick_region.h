// BrickRegion: the cells of one whole brick written into a box's row-major array of p, sixteen at a
// time, for region queries (Shard::PredictBox).
//
// A brick's 512 handles are in Morton order; a box is row-major. Walking the box and looking up each
// cell's handle costs a dozen instructions a cell, most of a region's time on a map of mostly
// never-changed cells. But sixteen consecutive handles of a brick are a 4×4 block of a flat brick
// (key bits x0 y0 x1 y1) or a 4×2×2 block of a cubic one (x0 y0 z0 x1): four rows of four cells.
// So a whole brick goes sixteen handles at a time: four loads, their values (a never-changed
// cell's bit as 0 or 1, an unobserved cell's 0.5) converted together, two shuffles into four rows,
// four stores; the dynamic handles among the sixteen (a mask of their sign bits) go to the caller,
// which predicts them and overwrites their cells. A brick only partly in the box is the caller's.
//
// Handles as the shard keeps them: kNoHandle (unobserved), kNeverChanged | value, or a dynamic
// state's index (top bit clear).
//
// The box's array holds p as float, or quantised as bytes (CellValue<uint8_t>, the UINT8 region
// output), so that a UINT8 region is written once, in its wire form, rather than as floats first.
// BoxBricks, beside it, numbers the bricks a box overlaps, so that the cells of bricks no shard
// holds are filled after the shards have written theirs.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

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

class BrickRegion {
 public:
  static constexpr uint32_t kNoHandle = UINT32_MAX;
  static constexpr uint32_t kNeverChanged = 0x80000000u;

  // For a box nx cells along x and ny along y, of a grid keyed by `keys`.
  BrickRegion(const GridKeys& keys, uint64_t nx, uint64_t ny);

  // Position of the brick's cell with handle index i relative to the brick's first cell (its lowest
  // x, y, z), in the box's row-major order.
  int64_t offset(uint32_t i) const { return offset_[i]; }

  // Writes p of each never-changed and each unobserved cell of a whole brick, whose first cell is
  // at `origin` in the box, and calls on_dynamic(handle, T* cell) for each other cell, in handle
  // order. The dynamic cells' values are left for the caller to write. T: float or uint8_t.
  // REQUIRES: the whole brick is inside the box.
  template <typename T, typename OnDynamic>
  void Write(const uint32_t* handles, T* origin, OnDynamic on_dynamic) const {
#if defined(__SSE2__)  // every x86-64
    WriteSixteenAtATime(handles, origin, on_dynamic);
#else
    WriteEachCell(handles, origin, on_dynamic);
#endif
  }

  // Write's two ways, the same result: public so that the tests compare both with the cell by cell
  // walk on any machine that has SSE2.
  template <typename T, typename OnDynamic>
  void WriteEachCell(const uint32_t* handles, T* origin, OnDynamic on_dynamic) const {
    for (uint32_t i = 0; i < 512; ++i) {
      const uint32_t h = handles[i];
      if (h & kNeverChanged) {
        origin[offset_[i]] = CellValue<T>(h == kNoHandle ? kUnobservedProbability : static_cast<float>(h & 1u));
      } else {
        on_dynamic(h, origin + offset_[i]);
      }
    }
  }
#if defined(__SSE2__)
  template <typename T, typename OnDynamic>
  void WriteSixteenAtATime(const uint32_t* handles, T* origin, OnDynamic on_dynamic) const;
#endif

 private:
#if defined(__SSE2__)
  // Four cells of a row, p in each lane.
  static void StoreRow(float* cells, __m128 p) { _mm_storeu_ps(cells, p); }
  // As four bytes: round(255·p) as QuantizeProbability makes it (p·255 + 0.5 truncated).
  static void StoreRow(uint8_t* cells, __m128 p) {
    const __m128i q = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(p, _mm_set1_ps(255.0f)), _mm_set1_ps(0.5f)));
    const __m128i halves = _mm_packs_epi32(q, q);
    const int32_t four = _mm_cvtsi128_si32(_mm_packus_epi16(halves, halves));
    std::memcpy(cells, &four, sizeof(four));
  }
#endif

  // Handle index of the first cell of row r (0..3) of a group of sixteen, relative to the group's
  // first: rows 0, 1 are lanes 0 and 2 of the first four handles; rows 2, 3 the same lanes of the
  // four handles that hold the other half of the block (the next y pair of a flat brick, z + 1 of
  // a cubic one).
  std::array<uint32_t, 4> row_start_;
  bool flat_;
  std::array<int64_t, 512> offset_;
};

#if defined(__SSE2__)
template <typename T, typename OnDynamic>
void BrickRegion::WriteSixteenAtATime(const uint32_t* handles, T* origin, OnDynamic on_dynamic) const {
  const __m128i none = _mm_set1_epi32(-1), bit = _mm_set1_epi32(1);
  const __m128 unobserved = _mm_set1_ps(kUnobservedProbability);
  for (uint32_t g = 0; g < 512; g += 16) {
    __m128 v[4];
    uint32_t never_changed_or_none = 0;  // sign bits of the sixteen handles
    for (int q = 0; q < 4; ++q) {
      const __m128i h = _mm_loadu_si128(reinterpret_cast<const __m128i*>(handles + g + 4 * q));
      const __m128 is_none = _mm_castsi128_ps(_mm_cmpeq_epi32(h, none));
      const __m128 value = _mm_cvtepi32_ps(_mm_and_si128(h, bit));
      v[q] = _mm_or_ps(_mm_andnot_ps(is_none, value), _mm_and_ps(is_none, unobserved));
      never_changed_or_none |= static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(h))) << (4 * q);
    }
    // Flat (x0 y0 x1 y1): v[1] is v[0] at x + 2, v[3] is v[2] at x + 2. Cubic (x0 y0 z0 x1): v[2]
    // is v[0] at x + 2, v[3] is v[1] at x + 2.
    const __m128 a = v[0], b = flat_ ? v[1] : v[2], c = flat_ ? v[2] : v[1], d = v[3];
    StoreRow(origin + offset_[g + row_start_[0]], _mm_movelh_ps(a, b));
    StoreRow(origin + offset_[g + row_start_[1]], _mm_movehl_ps(b, a));
    StoreRow(origin + offset_[g + row_start_[2]], _mm_movelh_ps(c, d));
    StoreRow(origin + offset_[g + row_start_[3]], _mm_movehl_ps(d, c));
    for (uint32_t dynamic = ~never_changed_or_none & 0xffffu; dynamic != 0; dynamic &= dynamic - 1) {
      const uint32_t i = g + static_cast<uint32_t>(std::countr_zero(dynamic));
      on_dynamic(handles[i], origin + offset_[i]);
    }
  }
}
#endif

}  // namespace fremen::storage
