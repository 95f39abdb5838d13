// A box at many times as one dense array per time: PredictRegionSeries streams the base (which
// cells vary, the values of the others, once) and then, per time, the varying cells' values
// (proto/fremen/v1/query.proto); RegionSeriesAssembler rebuilds each time's frame and checks that
// the chunks fit — in order, no gap, no overlap, the values of the output kind asked for.
// Thread-compatible.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/lib/region_assembler.h"
#include "fremen/v1/query.pb.h"

namespace fremen::client {

struct RegionSeries {
  // frames[i]: the box at times[i], as PredictRegion at that time gives it.
  std::vector<RegionArray> frames;
  // Cells of the box whose prediction varies with time (sent once per time; the others once).
  uint64_t varying_cells = 0;
  // Values the stream carried: the constant cells once, the varying ones once per time.
  uint64_t values_received = 0;
};

class RegionSeriesAssembler {
 public:
  // `output` as asked for (UNSPECIFIED is FLOAT); `time_count` times asked for.
  RegionSeriesAssembler(GridShape shape, v1::RegionOutput output, uint32_t time_count);

  // One chunk, in stream order. DATA_LOSS naming what does not fit.
  absl::Status Add(const v1::PredictRegionSeriesResponse& chunk);
  // The frames; DATA_LOSS when values are missing. Leaves the assembler empty.
  absl::StatusOr<RegionSeries> Finish();

 private:
  absl::Status AddBase(const v1::PredictRegionSeriesResponse& chunk);
  absl::Status AddFrame(const v1::PredictRegionSeriesResponse& chunk);
  // Copies values[first, first + n) of a chunk into `array` at cells[k] for k < n.
  static void Scatter(const v1::PredictRegionSeriesResponse& chunk, uint64_t first, uint64_t n,
                      const uint64_t* cells, RegionArray& array);

  const uint32_t time_count_;
  RegionArray base_;               // the constant cells' values
  std::vector<uint64_t> varying_;  // the varying cells' indices in the box, in order
  uint64_t base_received_ = 0;     // cells of the box covered by base chunks
  uint64_t varying_cells_ = 0;     // as the stream says
  uint32_t time_ = 0;              // the frame being received
  uint64_t frame_received_ = 0;    // its values so far
  RegionSeries series_;
};

}  // namespace fremen::client
