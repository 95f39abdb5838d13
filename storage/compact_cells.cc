#include "storage/compact_cells.h"

#include <algorithm>

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

}  // namespace

absl::Status ExpandCompactCells(const GridGeometry& grid, const CompactCells& cells, uint64_t max_cells,
                                std::vector<uint64_t>& keys, std::vector<float>& values) {
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
  uint64_t key = 0;
  uint64_t index = 0;
  std::array<uint32_t, 3> cell = {0, 0, 0};
  bool outside = false;  // index ≥ cell_count: this and every later cell
  size_t at = 0;
  for (size_t i = 0; i < n; ++i) {
    if (i > 0 && !outside && in[at] == 1 && cell[0] + 1 < nx) {
      // A run of neighbours along x, the bulk of a coherent scan: one byte (gap 1) and one step of
      // the key's x bits each, up to the row's end, with none of the checks a gap needs.
      const size_t run_limit = std::min<size_t>(n - i, nx - 1 - cell[0]);
      size_t run = 1;
      while (run < run_limit && in[at + run] == 1) ++run;
      for (size_t r = 0; r < run; ++r) {
        key = (key & ~x_bits) | (((key | ~x_bits) + 1) & x_bits);
        keys[i + r] = key;
      }
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
  if (soft) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(cells.probabilities.data());
    for (size_t i = 0; i < n; ++i) values[i] = bytes[i] / 255.0f;  // exactly rounded, as a patch's bytes
  } else {
    for (size_t i = 0; i < n; ++i) values[i] = static_cast<float>((bits[i / 8] >> (i % 8)) & 1);
  }
  return absl::OkStatus();
}

}  // namespace fremen::storage
