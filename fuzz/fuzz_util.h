// What the fuzz targets share: a check that makes libFuzzer report a crash with a message, and the
// maps and views the targets feed their inputs through. Header-only; each target is one process and
// single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "storage/map_info.h"

namespace fremen::fuzz {

// A property every input must keep (a round trip, a bound): a violation aborts, which libFuzzer
// reports as a crash and saves the input for.
#define FUZZ_CHECK(condition, what)                                                                \
  do {                                                                                             \
    if (!(condition)) {                                                                            \
      std::fprintf(stderr, "FUZZ_CHECK failed at %s:%d: %s: %s\n", __FILE__, __LINE__, #condition, \
                   std::string(what).c_str());                                                     \
      std::abort();                                                                                \
    }                                                                                              \
  } while (0)

inline std::string_view AsView(const uint8_t* data, size_t size) { return {reinterpret_cast<const char*>(data), size}; }

// The maps the converters are fed against, chosen by a byte of the input: a 2-D grid, a 3-D grid
// and a generic map, all valid (ValidateMapInfo) with small grids so that whole-grid loops stay
// fast.
inline storage::MapInfo FuzzMap(uint8_t choice) {
  storage::MapInfo info;
  info.name = "fuzz";
  info.id = 7;
  info.shards = 2;
  switch (choice % 3) {
    case 0:
      info.grid.resolution = 0.05;
      info.grid.origin = {-1.5, 2.25, 0};
      info.grid.size = {64, 48, 1};
      break;
    case 1:
      info.grid.resolution = 0.2;
      info.grid.size = {16, 12, 8};
      info.max_order = 3;
      info.persistence = false;
      break;
    default:
      info.kind = storage::MapKind::kGeneric;
      info.lossless_sampling_period = 60;
      info.lossless_origin = 1.7e9;
      break;
  }
  return info;
}

}  // namespace fremen::fuzz
