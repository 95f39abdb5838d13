// PredictRegionSeries: a box of a grid at many times, as a BlockStream
// (server/services/block_stream.h), in the layout query.proto documents: the base — which cells
// vary with time, and the values of the others — once, then per time the varying cells' values.
//
// Block 0 plans the box (MapStore::PlanBoxSeries: one pass over it) and cuts the base into chunks;
// each later block predicts the varying cells at a few consecutive times (MapStore::
// PredictBoxSeries: one phasor table a time, the shards in parallel, each model record read once
// for the block's times) and cuts them into chunks, time by time. Memory: the plan (about 20 bytes
// a cell of the box, hence the bound on the box) and a block's values (at most
// kSeriesBlockValues floats, or one time's).
//
// Thread-safety: as BlockStream's.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "fremen/v1/query.pb.h"
#include "server/rpc/unary_call.h"
#include "server/services/block_stream.h"
#include "storage/map_store.h"

namespace fremen::server {

// The most cells of a series' box (its plan holds ~20 bytes a cell: 80 MiB at most), and times.
inline constexpr uint64_t kMaxSeriesCells = uint64_t{1} << 22;
inline constexpr int kMaxSeriesTimes = 1000;

// Values one block of times predicts at most (4 MiB of floats), and its most times: enough times
// that a block's records, read at its first time, serve the others from cache (a 1M-cell box with
// 12 % varying cells: 8 times a block), few enough that memory stays bounded.
inline constexpr uint64_t kSeriesBlockValues = uint64_t{1} << 20;
inline constexpr uint64_t kMaxSeriesTimesPerBlock = 16;

class RegionSeriesStream final
    : public BlockStream<v1::PredictRegionSeriesRequest, v1::PredictRegionSeriesResponse> {
 public:
  // Starts the call; the reactor deletes itself once the call is done.
  static RegionSeriesStream* Start(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                   const grpc::ByteBuffer& request);

 private:
  RegionSeriesStream(const ServiceDeps& deps, grpc::CallbackServerContext* context);
  absl::Status Prepare(const v1::PredictRegionSeriesRequest& request) override;
  absl::Status ComputeBlock(uint64_t i, Chunks& chunks, uint64_t& more_blocks) override;
  bool ComputesInline(uint64_t i) const override;
  // Block 0: the plan and the base's chunks.
  absl::Status ComputeBase(Chunks& chunks);
  // message_, cleared, with the fields every message repeats.
  Response& NewChunk();

  // Fixed by Prepare.
  std::shared_ptr<storage::MapStore> map_;
  storage::CellBox box_;
  storage::PredictOptions options_;
  std::vector<double> times_;
  v1::RegionOutput output_ = v1::REGION_OUTPUT_FLOAT;
  float confidence_ = 0.5f;
  uint64_t chunk_cells_ = 0;  // values per frame chunk

  // Block 0's, read by the later blocks (one computation at a time, in order).
  std::optional<storage::BoxSeries> plan_;
  uint64_t times_per_block_ = 1;
  // The computing thread's.
  std::vector<float> scratch_;
  Response message_;  // the chunk being made
};

}  // namespace fremen::server
