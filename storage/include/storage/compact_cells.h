// A scan of grid cells in the compact form of the API (proto CompactCells): strictly increasing
// linear cell indices x + size.x·(y + size.y·z) as varints of their gaps, and one bit per cell for
// binary observations or one byte per cell for soft ones. About 1.1 bytes per binary observation
// of a coherent scan, against 5 for keys and floats; the log keeps this form as it came
// (docs/storage.md, "Batch record"), and it is expanded into keys and values only to be applied.
// Value type and pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "base/uninitialized_vector.h"
#include "storage/map_info.h"

namespace fremen::storage {

struct CompactCells {
  std::string indices;        // varints: the first linear index, then each gap to the next (≥ 1)
  std::string occupied;       // ceil(n / 8) bytes: cell i is bit i % 8 of byte i / 8; unused bits 0
  std::string probabilities;  // n bytes, s = byte / 255; empty when `occupied` holds the values
  bool empty() const { return indices.empty() && occupied.empty() && probabilities.empty(); }
  bool operator==(const CompactCells&) const = default;
};

// The key every cell outside the grid gets: no cell's key, so that Classify rejects it as outside
// the map, per observation, as for cells given by index.
inline constexpr uint64_t kNotACellKey = ~uint64_t{0};

// The keys and values of `cells` in `grid`, into `keys` and `values` (resized to the cell count; a
// cell past the grid's last gets kNotACellKey, and `outside`, when given, their count: indices
// increase, so they are the last cells).
// InvalidArgument naming the field ("compact.indices", "compact.occupied", "compact.probabilities")
// on a truncated or overlong varint, a gap of 0 (indices not increasing), a value array of the
// wrong length, set unused bits, both or neither value array, or more than `max_cells` cells.
absl::Status ExpandCompactCells(const GridGeometry& grid, const CompactCells& cells, uint64_t max_cells,
                                UninitializedVector<uint64_t>& keys, UninitializedVector<float>& values,
                                size_t* outside = nullptr);

}  // namespace fremen::storage
