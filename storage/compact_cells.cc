#include "storage/compact_cells.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "storage/cell_key.h"

namespace fremen::storage {

namespace {

absl::Status Invalid(auto&&... parts) { return absl::InvalidArgumentError(absl::StrCat(parts...)); }

// The cell (x, y, z) of a linear index below the grid's cell count.
std::array<uint32_t, 3> CellOfIndex(const GridGeometry& grid, uint64_t index) {
  const uint64_t layer = uint64_t{grid.size[0]} * grid.size[1];
  return {static_cast<uint32_t>(index % grid.size[0]), static_cast<uint32_t>(index % layer / grid.size[0]),
          static_cast<uint32_t>(index / layer)};
}

// The key bits of an x offset 0..255, spread as in a 2-D key (x in the even bits) and in a 3-D one
// (every third bit): a key along a row is the row's other bits | the spread x's high part | these.
struct SpreadLowX {
  std::array<uint64_t, 256> flat, cube;
};
const SpreadLowX& SpreadLowXTable() {
  static const SpreadLowX table = [] {
    SpreadLowX t;
    for (uint64_t x = 0; x < 256; ++x) {
      t.flat[x] = SpreadBits2(x);
      t.cube[x] = SpreadBits3(x);
    }
    return t;
  }();
  return table;
}

// Each byte of occupied bits as the 8 floats 0 or 1 it stands for, cell i % 8 at [i % 8].
using BitFloats = std::array<std::array<float, 8>, 256>;
const BitFloats& BitFloatsTable() {
  static const BitFloats table = [] {
    BitFloats t;
    for (uint32_t byte = 0; byte < 256; ++byte) {
      for (uint32_t bit = 0; bit < 8; ++bit) t[byte][bit] = static_cast<float>((byte >> bit) & 1);
    }
    return t;
  }();
  return table;
}

// The length of the run of gap-1 bytes at `in`, up to `limit` (REQUIRES: in[0..limit) readable),
// eight at a time while they last.
size_t RunOfOnes(const uint8_t* in, size_t limit) {
  constexpr uint64_t kEightOnes = 0x0101010101010101ull;
  size_t run = 0;
  for (uint64_t eight; run + 8 <= limit; run += 8) {
    std::memcpy(&eight, in + run, 8);
    if (eight != kEightOnes) break;
  }
  while (run < limit && in[run] == 1) ++run;
  return run;
}

}  // namespace

absl::Status ExpandCompactCells(const GridGeometry& grid, const CompactCells& cells, uint64_t max_cells,
                                UninitializedVector<uint64_t>& keys, UninitializedVector<float>& values,
                                size_t* outside_count) {
  const bool soft = !cells.probabilities.empty();
  if (soft && !cells.occupied.empty()) return Invalid("compact: set occupied or probabilities, not both");
  const auto* in = reinterpret_cast<const uint8_t*>(cells.indices.data());
  const size_t length = cells.indices.size();
  // Every varint ends in the one byte of it without the continuation bit: counting those counts
  // the cells, and once the last byte is such an end, no varint can run past the bytes.
  size_t n = 0;
  for (size_t i = 0; i < length; ++i) n += in[i] < 0x80;
  if (length > 0 && in[length - 1] >= 0x80) {
    return Invalid("compact.indices: the last varint is truncated (its last byte has the continuation bit set)");
  }
  if (n > max_cells) return Invalid("compact.indices holds ", n, " cells; a batch may hold at most ", max_cells);
  if (n > 0 && !soft && cells.occupied.empty()) {
    return Invalid("compact: one of occupied or probabilities is required for the ", n, " cells");
  }
  if (soft && cells.probabilities.size() != n) {
    return Invalid("compact.probabilities has ", cells.probabilities.size(), " bytes for ", n,
                   " cells (compact.indices); want one per cell");
  }
  if (!soft && cells.occupied.size() != (n + 7) / 8) {
    return Invalid("compact.occupied has ", cells.occupied.size(), " bytes for ", n,
                   " cells (compact.indices); want one bit per cell, ", (n + 7) / 8, " bytes");
  }
  const auto* bits = reinterpret_cast<const uint8_t*>(cells.occupied.data());
  if (!soft && n % 8 != 0 && (bits[n / 8] >> (n % 8)) != 0) {
    return Invalid("compact.occupied: the bits past the last cell (", n, ") must be 0");
  }

  keys.resize(n);
  values.resize(n);
  const GridKeys layout = grid.keys();
  const uint64_t cell_count = grid.cell_count();
  const uint32_t nx = grid.size[0];
  // The key's x bits (Morton: every third bit in 3-D, every second in 2-D). A step of one along x
  // adds 1 to them alone: set the other bits so that the carry skips them, add, keep the x bits.
  const uint64_t x_bits = layout.flat() ? 0x5555555555555555ull : 0x1249249249249249ull;
  const std::array<uint64_t, 256>& spread_low_x = layout.flat() ? SpreadLowXTable().flat : SpreadLowXTable().cube;
  uint64_t key = 0;
  uint64_t index = 0;
  std::array<uint32_t, 3> cell = {0, 0, 0};
  bool outside = false;  // index ≥ cell_count: this and every later cell
  size_t first_outside = n;
  size_t at = 0;
  for (size_t i = 0; i < n; ++i) {
    if (i > 0 && !outside && in[at] == 1 && cell[0] + 1 < nx) {
      // A run of neighbours along x, the bulk of a coherent scan: one byte (gap 1) each, up to the
      // row's end, with none of the checks a gap needs. Every cell left in the batch has a byte at
      // least, so the run's bytes are there. Its keys are the row's bits | x's, x's looked up 256
      // at a time: no chain of dependent steps from one key to the next, as stepping the key's x
      // bits made.
      const size_t run_limit = std::min<size_t>(n - i, nx - 1 - cell[0]);
      const size_t run = RunOfOnes(in + at, run_limit);
      const uint64_t row_bits = key & ~x_bits;
      uint32_t x = cell[0] + 1;
      for (size_t r = 0; r < run;) {
        const uint64_t high = row_bits | layout.Key(x & ~255u, 0, 0);
        const size_t stop = std::min<size_t>(run, r + (256 - (x & 255)));
        for (; r < stop; ++r, ++x) keys[i + r] = high | spread_low_x[x & 255];
      }
      key = keys[i + run - 1];
      at += run;
      index += run;
      cell[0] += static_cast<uint32_t>(run);
      i += run - 1;
      continue;
    }
    uint64_t gap = in[at++];
    if (gap >= 0x80) {  // the rare long gap: a jump to another part of the grid
      gap &= 0x7f;
      int shift = 7;
      uint8_t byte;
      do {
        byte = in[at++];
        if (shift == 63 && byte > 1) return Invalid("compact.indices: the varint of cell ", i, " exceeds 64 bits");
        gap |= uint64_t{byte & 0x7fu} << shift;
        shift += 7;
      } while (byte >= 0x80);
      if (byte == 0) return Invalid("compact.indices: the varint of cell ", i, " is not in its shortest form");
    }
    if (gap == 0 && i > 0) {
      return Invalid("compact.indices: the gap before cell ", i, " is 0; indices must increase strictly");
    }
    if (!outside && (i == 0 || gap >= cell_count - index)) {
      if (gap >= cell_count - index) {
        outside = true;
        first_outside = i;
      } else {
        index += gap;
        cell = CellOfIndex(grid, index);
      }
    } else if (!outside) {
      index += gap;
      // Along a row the cell moves in x alone; a gap that leaves the row is recomputed.
      if (gap < nx - cell[0]) {
        cell[0] += static_cast<uint32_t>(gap);
        if (gap == 1) {  // the common step of a coherent scan: the key's x bits plus one
          key = (key & ~x_bits) | (((key | ~x_bits) + 1) & x_bits);
          keys[i] = key;
          continue;
        }
      } else {
        cell = CellOfIndex(grid, index);
      }
    }
    key = outside ? kNotACellKey : layout.Key(cell[0], cell[1], cell[2]);
    keys[i] = key;
  }
  if (outside_count != nullptr) *outside_count = n - first_outside;
  if (soft) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(cells.probabilities.data());
    for (size_t i = 0; i < n; ++i) values[i] = bytes[i] / 255.0f;  // exactly rounded, as a patch's bytes
  } else {
    const BitFloats& bit_floats = BitFloatsTable();
    const size_t whole_bytes = n / 8;
    for (size_t b = 0; b < whole_bytes; ++b) std::memcpy(&values[8 * b], bit_floats[bits[b]].data(), 8 * sizeof(float));
    for (size_t i = 8 * whole_bytes; i < n; ++i) values[i] = static_cast<float>((bits[i / 8] >> (i % 8)) & 1);
  }
  return absl::OkStatus();
}

}  // namespace fremen::storage
