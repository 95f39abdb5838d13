#include "client/lib/region_assembler.h"

#include <utility>

#include "absl/strings/str_cat.h"

namespace fremen::client {

RegionAssembler::RegionAssembler(GridShape shape, v1::RegionOutput output) {
  array_.shape = shape;
  array_.output = output == v1::REGION_OUTPUT_UNSPECIFIED ? v1::REGION_OUTPUT_FLOAT : output;
  if (array_.is_float()) {
    array_.floats.resize(shape.cells());
  } else {
    array_.bytes.resize(shape.cells());
  }
}

absl::Status RegionAssembler::Add(const v1::PredictRegionResponse& chunk) {
  const uint64_t total = array_.shape.cells();
  if (chunk.box_cells() != total) {
    return absl::DataLossError(absl::StrCat("region chunk says the box has ", chunk.box_cells(), " cells, not ", total));
  }
  if (chunk.offset() != received_) {
    return absl::DataLossError(absl::StrCat("region chunk at offset ", chunk.offset(), " where ", received_,
                                            " was expected (chunks come in order, without gaps)"));
  }
  const bool floats = array_.is_float();
  if ((floats && !chunk.bytes_values().empty()) || (!floats && chunk.float_values_size() > 0)) {
    return absl::DataLossError("region chunk holds values of another output kind than asked for");
  }
  const uint64_t n = floats ? chunk.float_values_size() : chunk.bytes_values().size();
  if (n == 0 || received_ + n > total) {
    return absl::DataLossError(absl::StrCat("region chunk of ", n, " cells at offset ", received_,
                                            " does not fit the box of ", total, " cells"));
  }
  if (floats) {
    std::copy(chunk.float_values().begin(), chunk.float_values().end(), array_.floats.begin() + received_);
  } else {
    std::copy(chunk.bytes_values().begin(), chunk.bytes_values().end(), array_.bytes.begin() + received_);
  }
  received_ += n;
  return absl::OkStatus();
}

absl::StatusOr<RegionArray> RegionAssembler::Finish() {
  if (received_ != array_.shape.cells()) {
    return absl::DataLossError(
        absl::StrCat("the region stream ended after ", received_, " of ", array_.shape.cells(), " cells"));
  }
  received_ = 0;
  return std::exchange(array_, RegionArray{});
}

}  // namespace fremen::client
