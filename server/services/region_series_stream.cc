#include "server/services/region_series_stream.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "server/convert/query_args.h"
#include "server/services/region_plan.h"
#include "server/services/region_request.h"

namespace fremen::server {

namespace {

constexpr MethodSpec kPredictRegionSeries{"PredictRegionSeries", Access::kRead, /*blocking=*/true};

uint64_t CeilDiv(uint64_t a, uint64_t b) { return (a + b - 1) / b; }

}  // namespace

RegionSeriesStream::RegionSeriesStream(const ServiceDeps& deps, grpc::CallbackServerContext* context)
    : BlockStream(deps, context, kPredictRegionSeries) {}

RegionSeriesStream* RegionSeriesStream::Start(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                              const grpc::ByteBuffer& request) {
  auto* stream = new RegionSeriesStream(deps, context);
  stream->Begin(request);
  return stream;
}

absl::Status RegionSeriesStream::Prepare(const v1::PredictRegionSeriesRequest& request) {
  auto region = PrepareRegion(*deps_.store, *context_, request.map(), request.lo(), request.hi(), request.options(),
                              request.output(), request.confidence());
  if (!region.ok()) return region.status();
  if (region->box.cell_count() > kMaxSeriesCells) {
    return absl::OutOfRangeError(absl::StrCat("the box [lo, hi) of PredictRegionSeries must hold at most ",
                                              kMaxSeriesCells, " cells, got ", region->box.cell_count(),
                                              ": split it"));
  }
  if (request.times().empty() || request.times_size() > kMaxSeriesTimes) {
    return absl::InvalidArgumentError(
        absl::StrCat("times must hold 1 to ", kMaxSeriesTimes, " times, got ", request.times_size()));
  }
  if (absl::Status s = CheckTimes(SpanOf(request.times()), "times"); !s.ok()) return s;
  map_ = std::move(region->map);
  box_ = region->box;
  options_ = region->options;
  output_ = region->output;
  confidence_ = request.confidence();
  times_.assign(request.times().begin(), request.times().end());
  chunk_cells_ = ChunkCells(request.chunk_cells(), output_);
  // Block 0 (the base); it adds the frames' blocks once it knows the varying cells. A block's
  // chunks: the base's, or a block of times' (each time's varying cells, at most the box).
  SetBlocks(1, std::max(CeilDiv(box_.cell_count(), BaseChunkCells(chunk_cells_, output_)),
                        kMaxSeriesTimesPerBlock * CeilDiv(box_.cell_count(), chunk_cells_)));
  set_total_values(box_.cell_count());
  return absl::OkStatus();
}

bool RegionSeriesStream::ComputesInline(uint64_t i) const {
  // plan_ is set by block 0, before block 1 is asked for.
  const uint64_t cells = i == 0 ? box_.cell_count() : plan_->varying.size() * times_per_block_;
  return cells <= kInlineRegionCells;
}

v1::PredictRegionSeriesResponse& RegionSeriesStream::NewChunk() {
  message_.Clear();
  message_.set_box_cells(box_.cell_count());
  message_.set_varying_cells(plan_->varying.size());
  message_.set_time_count(static_cast<uint32_t>(times_.size()));
  return message_;
}

absl::Status RegionSeriesStream::ComputeBase(Chunks& chunks) {
  auto plan = map_->PlanBoxSeries(box_, times_[0], options_);
  if (!plan.ok()) return plan.status();
  plan_ = *std::move(plan);
  const std::vector<uint32_t>& varying = plan_->varying;
  set_total_values(box_.cell_count() - varying.size() + varying.size() * times_.size());
  const uint64_t per_chunk = BaseChunkCells(chunk_cells_, output_);
  auto next_varying = varying.begin();
  for (uint64_t offset = 0; offset < box_.cell_count(); offset += per_chunk) {
    const uint64_t cells = std::min(per_chunk, box_.cell_count() - offset);
    Response& chunk = NewChunk();
    chunk.set_base(true);
    chunk.set_offset(offset);
    chunk.set_cells(cells);
    std::string& mask = *chunk.mutable_varying_mask();
    mask.assign(CeilDiv(cells, 8), '\0');
    scratch_.clear();
    // Runs of constant cells between the chunk's varying ones.
    uint64_t from = offset;
    const auto constant_run = [&](uint64_t to) {
      scratch_.insert(scratch_.end(), plan_->constant.begin() + from, plan_->constant.begin() + to);
    };
    for (; next_varying != varying.end() && *next_varying < offset + cells; ++next_varying) {
      const uint64_t j = *next_varying - offset;
      mask[j / 8] = static_cast<char>(mask[j / 8] | (1 << (j % 8)));
      constant_run(*next_varying);
      from = *next_varying + 1;
    }
    constant_run(offset + cells);
    EncodeRegionValues(output_, confidence_, scratch_, chunk);
    if (absl::Status s = AddChunk(chunk, chunks); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status RegionSeriesStream::ComputeBlock(uint64_t i, Chunks& chunks, uint64_t& more_blocks) {
  if (i == 0) {
    if (absl::Status s = ComputeBase(chunks); !s.ok()) return s;
    // Blocks of a few times; none when nothing varies.
    const uint64_t varying = plan_->varying.size();
    if (varying > 0) {
      times_per_block_ = std::clamp<uint64_t>(kSeriesBlockValues / varying, 1, kMaxSeriesTimesPerBlock);
      more_blocks = CeilDiv(times_.size(), times_per_block_);
    }
    return absl::OkStatus();
  }
  const uint64_t first = (i - 1) * times_per_block_;
  const uint64_t count = std::min<uint64_t>(times_per_block_, times_.size() - first);
  map_->PredictBoxSeries(*plan_, std::span<const double>(times_).subspan(first, count), scratch_);
  const uint64_t varying = plan_->varying.size();
  for (uint64_t g = 0; g < count; ++g) {
    const std::span<const float> frame = std::span<const float>(scratch_).subspan(g * varying, varying);
    for (uint64_t offset = 0; offset < varying; offset += chunk_cells_) {
      const uint64_t n = std::min(chunk_cells_, varying - offset);
      Response& chunk = NewChunk();
      chunk.set_time_index(static_cast<uint32_t>(first + g));
      chunk.set_offset(offset);
      EncodeRegionValues(output_, confidence_, frame.subspan(offset, n), chunk);
      if (absl::Status s = AddChunk(chunk, chunks); !s.ok()) return s;
    }
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
