#include "server/services/region_stream.h"

#include <span>
#include <string>

#include "server/convert/query_args.h"
#include "server/services/region_request.h"

namespace fremen::server {

namespace {

constexpr MethodSpec kPredictRegion{"PredictRegion", Access::kRead, /*blocking=*/true};

}  // namespace

RegionStream::RegionStream(const ServiceDeps& deps, grpc::CallbackServerContext* context)
    : BlockStream(deps, context, kPredictRegion) {}

RegionStream* RegionStream::Start(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                  const grpc::ByteBuffer& request) {
  auto* stream = new RegionStream(deps, context);
  stream->Begin(request);
  return stream;
}

absl::Status RegionStream::Prepare(const v1::PredictRegionRequest& request) {
  auto region = PrepareRegion(*deps_.store, *context_, request.map(), request.lo(), request.hi(), request.options(),
                              request.output(), request.confidence());
  if (!region.ok()) return region.status();
  map_ = std::move(region->map);
  options_ = region->options;
  output_ = region->output;
  confidence_ = request.confidence();
  if (absl::Status s = CheckTime(request.time(), "time"); !s.ok()) return s;
  time_ = request.time();
  blocks_.emplace(region->box, kRegionBlockCells);
  chunk_cells_ = ChunkCells(request.chunk_cells(), output_);
  SetBlocks(blocks_->chunk_count(),
            (std::min(kRegionBlockCells, region->box.cell_count()) + chunk_cells_ - 1) / chunk_cells_);
  set_total_values(blocks_->box_cells());
  return absl::OkStatus();
}

bool RegionStream::ComputesInline(uint64_t i) const {
  return blocks_->chunk(i).box.cell_count() <= kInlineRegionCells;
}

absl::Status RegionStream::ComputeBlock(uint64_t i, Chunks& chunks, uint64_t& /*more_blocks*/) {
  const RegionPlan::Chunk block = blocks_->chunk(i);
  // A block is a run of the box's cells in the box's order, and so is each chunk of the block.
  const RegionPlan plan(block.box, chunk_cells_);
  const bool floats = output_ == v1::REGION_OUTPUT_FLOAT, bytes = output_ == v1::REGION_OUTPUT_UINT8;
  // Floats and bytes are predicted straight into each chunk's place on the wire (bytes quantised by
  // the shards as they write); the other outputs are computed from the block's p, predicted once
  // into scratch_.
  if (!floats && !bytes) {
    if (absl::Status s = map_->PredictBox(block.box, time_, options_, scratch_); !s.ok()) return s;
  }
  for (uint64_t j = 0; j < plan.chunk_count(); ++j) {
    const RegionPlan::Chunk chunk = plan.chunk(j);
    const uint64_t cells = chunk.box.cell_count();
    message_.Clear();
    message_.set_offset(block.offset + chunk.offset);
    message_.set_box_cells(blocks_->box_cells());
    if (floats || bytes) {
      ValuesInPlace values(message_, floats ? Response::kFloatValuesFieldNumber : Response::kBytesValuesFieldNumber,
                           floats ? cells * sizeof(float) : cells);
      const absl::Status s = floats ? map_->PredictBox(chunk.box, time_, options_, values.floats())
                                    : map_->PredictBox(chunk.box, time_, options_, values.bytes());
      if (!s.ok()) return s;
      chunks.push_back(std::move(values).Finish(cells));
      continue;
    }
    EncodeRegionValues(output_, confidence_, std::span<const float>(scratch_).subspan(chunk.offset, cells),
                       message_);
    if (absl::Status s = AddChunk(message_, chunks); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
