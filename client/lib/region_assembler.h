// A predicted region as one dense array: PredictRegion streams the box in chunks (runs of cells,
// x fastest, then y, then z); RegionAssembler puts them together and checks that they fit —
// in order, no gap, no overlap, the values of the output kind asked for, the whole box.
// Thread-compatible.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/lib/state_set.h"
#include "fremen/v1/query.pb.h"

namespace fremen::client {

// A box of a grid at one time. Cell (x, y, z) of the box (relative to its lo corner) is at
// Index(x, y, z).
struct RegionArray {
  GridShape shape;
  // FLOAT and ENTROPY fill `floats`; UINT8 (round(255·p)) and STATES (0/1) fill `bytes`.
  v1::RegionOutput output = v1::REGION_OUTPUT_FLOAT;
  std::vector<float> floats;
  std::vector<uint8_t> bytes;

  uint64_t Index(uint32_t x, uint32_t y, uint32_t z = 0) const {
    return x + uint64_t{shape.x} * (y + uint64_t{shape.y} * z);
  }
  bool is_float() const { return output != v1::REGION_OUTPUT_UINT8 && output != v1::REGION_OUTPUT_STATES; }
};

class RegionAssembler {
 public:
  // `output` as asked for (UNSPECIFIED is FLOAT).
  RegionAssembler(GridShape shape, v1::RegionOutput output);

  // One chunk, in stream order. DATA_LOSS naming what does not fit.
  absl::Status Add(const v1::PredictRegionResponse& chunk);
  // The array; DATA_LOSS when cells are missing. Leaves the assembler empty.
  absl::StatusOr<RegionArray> Finish();

 private:
  RegionArray array_;
  uint64_t received_ = 0;
};

}  // namespace fremen::client
