// The maps the storage and server fuzzers decode and convert against (FuzzMap). Apart from
// fuzz_util.h so that the targets of client/formats, which do not link storage, need not see it.
#pragma once

#include <cstdint>

#include "storage/map_info.h"

namespace fremen::fuzz {

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
