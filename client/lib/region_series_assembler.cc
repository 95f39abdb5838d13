#include "client/lib/region_series_assembler.h"

#include <utility>

#include "absl/strings/str_cat.h"

namespace fremen::client {

namespace {

uint64_t ValuesIn(const v1::PredictRegionSeriesResponse& chunk) {
  return chunk.float_values_size() + chunk.bytes_values().size();
}

}  // namespace

RegionSeriesAssembler::RegionSeriesAssembler(GridShape shape, v1::RegionOutput output, uint32_t time_count)
    : time_count_(time_count) {
  base_.shape = shape;
  base_.output = output == v1::REGION_OUTPUT_UNSPECIFIED ? v1::REGION_OUTPUT_FLOAT : output;
  if (base_.is_float()) {
    base_.floats.resize(shape.cells());
  } else {
    base_.bytes.resize(shape.cells());
  }
}

void RegionSeriesAssembler::Scatter(const v1::PredictRegionSeriesResponse& chunk, uint64_t first, uint64_t n,
                                    const uint64_t* cells, RegionArray& array) {
  if (array.is_float()) {
    for (uint64_t k = 0; k < n; ++k) array.floats[cells[k]] = chunk.float_values(static_cast<int>(first + k));
  } else {
    const auto* bytes = reinterpret_cast<const uint8_t*>(chunk.bytes_values().data()) + first;
    for (uint64_t k = 0; k < n; ++k) array.bytes[cells[k]] = bytes[k];
  }
}

absl::Status RegionSeriesAssembler::Add(const v1::PredictRegionSeriesResponse& chunk) {
  const uint64_t total = base_.shape.cells();
  if (chunk.box_cells() != total || chunk.time_count() != time_count_ || chunk.varying_cells() > total) {
    return absl::DataLossError(absl::StrCat("region series chunk says the box has ", chunk.box_cells(), " cells (",
                                            chunk.varying_cells(), " varying) at ", chunk.time_count(),
                                            " times, not ", total, " cells at ", time_count_, " times"));
  }
  const bool floats = base_.is_float();
  if ((floats && !chunk.bytes_values().empty()) || (!floats && chunk.float_values_size() > 0)) {
    return absl::DataLossError("region series chunk holds values of another output kind than asked for");
  }
  return chunk.base() ? AddBase(chunk) : AddFrame(chunk);
}

absl::Status RegionSeriesAssembler::AddBase(const v1::PredictRegionSeriesResponse& chunk) {
  const uint64_t total = base_.shape.cells();
  if (chunk.offset() != base_received_ || chunk.cells() == 0 || chunk.cells() > total - base_received_ ||
      chunk.varying_mask().size() != (chunk.cells() + 7) / 8) {
    return absl::DataLossError(absl::StrCat("region series base chunk of ", chunk.cells(), " cells (mask of ",
                                            chunk.varying_mask().size(), " bytes) at offset ", chunk.offset(),
                                            " where ", base_received_, " of ", total, " was expected"));
  }
  std::vector<uint64_t> constant;
  for (uint64_t j = 0; j < chunk.cells(); ++j) {
    const bool varies = (static_cast<uint8_t>(chunk.varying_mask()[j / 8]) >> (j % 8)) & 1;
    (varies ? varying_ : constant).push_back(chunk.offset() + j);
  }
  const uint64_t n = ValuesIn(chunk);
  if (n != constant.size()) {
    return absl::DataLossError(absl::StrCat("region series base chunk at offset ", chunk.offset(), " has ", n,
                                            " values for ", constant.size(), " constant cells"));
  }
  Scatter(chunk, 0, n, constant.data(), base_);
  base_received_ += chunk.cells();
  series_.values_received += n;
  varying_cells_ = chunk.varying_cells();
  if (base_received_ == total && varying_.size() != varying_cells_) {
    return absl::DataLossError(absl::StrCat("region series base marks ", varying_.size(),
                                            " varying cells where the stream says ", varying_cells_));
  }
  return absl::OkStatus();
}

absl::Status RegionSeriesAssembler::AddFrame(const v1::PredictRegionSeriesResponse& chunk) {
  const uint64_t n = ValuesIn(chunk);
  if (base_received_ != base_.shape.cells() || chunk.time_index() != time_ || time_ >= time_count_ ||
      chunk.offset() != frame_received_ || n == 0 || n > varying_.size() - frame_received_) {
    return absl::DataLossError(absl::StrCat("region series frame chunk of ", n, " values at time ",
                                            chunk.time_index(), " offset ", chunk.offset(), " where time ", time_,
                                            " offset ", frame_received_, " of ", varying_.size(),
                                            " was expected (the base first, then the times in order)"));
  }
  if (frame_received_ == 0) series_.frames.push_back(base_);
  Scatter(chunk, 0, n, varying_.data() + frame_received_, series_.frames.back());
  frame_received_ += n;
  series_.values_received += n;
  if (frame_received_ == varying_.size()) {
    ++time_;
    frame_received_ = 0;
  }
  return absl::OkStatus();
}

absl::StatusOr<RegionSeries> RegionSeriesAssembler::Finish() {
  const bool complete = base_received_ == base_.shape.cells() && (varying_.empty() || time_ == time_count_);
  if (!complete) {
    return absl::DataLossError(absl::StrCat("the region series stream ended after ", base_received_, " of ",
                                            base_.shape.cells(), " base cells and ", time_, " of ", time_count_,
                                            " frames"));
  }
  if (varying_.empty()) series_.frames.assign(time_count_, base_);
  series_.varying_cells = varying_.size();
  return std::exchange(series_, RegionSeries{});
}

}  // namespace fremen::client
