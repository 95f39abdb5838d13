#include "server/services/region_stream.h"

#include <chrono>

#include "absl/strings/str_cat.h"
#include "server/rpc/map_lookup.h"
#include "server/convert/query_args.h"

namespace fremen::server {

namespace {

constexpr MethodSpec kPredictRegion{"PredictRegion", Access::kRead, /*blocking=*/true};

// Cells computed by one PredictBox call: large enough that the shards' threads pay off (~1 ms of
// work), small enough that a 1M-cell box is several blocks, so that computing the next overlaps
// sending this one (measured: 1M FLOAT cells 105M → 133-160M cells/s, UINT8 146M → 172-246M,
// against 1M-cell blocks), and memory stays bounded (1 MiB of floats a block).
constexpr uint64_t kBlockCells = uint64_t{1} << 18;

// A block this small is computed inline on the thread that asks for it (well under a millisecond):
// the hop to the pool would cost more than the work.
constexpr uint64_t kInlineCells = 1 << 15;

}  // namespace

RegionStream::RegionStream(const ServiceDeps& deps, grpc::CallbackServerContext* context)
    : deps_(deps), context_(context), record_(kPredictRegion.name, *context, deps.observer) {}

RegionStream* RegionStream::Start(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                  const v1::PredictRegionRequest& request) {
  auto* stream = new RegionStream(deps, context);
  absl::StatusOr<uint64_t> id = deps.calls->BeginStream(stream->drain_);
  absl::Status status = id.status();
  if (id.ok()) stream->stream_id_ = *id;
  if (status.ok()) status = deps.auth->Authorize(*context, kPredictRegion.access, kPredictRegion.name);
  if (status.ok()) status = stream->Prepare(request);
  if (!status.ok()) {
    {
      base::MutexLock lock(&stream->mutex_);  // OnCancel may already pump
      stream->finished_ = true;
    }
    stream->FinishWith(status);
    return stream;
  }
  stream->Pump();
  return stream;
}

absl::Status RegionStream::Prepare(const v1::PredictRegionRequest& request) {
  auto map = LookUpMap(*deps_.store, *context_, request.map());
  if (!map.ok()) return map.status();
  map_ = *std::move(map);
  const storage::MapInfo& info = map_->info();
  auto box = RegionBoxOf(info, request.lo(), request.hi());
  if (!box.ok()) return box.status();
  if (absl::Status s = CheckTime(request.time(), "time"); !s.ok()) return s;
  auto options = PredictOptionsOf(info, request.options(), "options");
  if (!options.ok()) return options.status();
  options_ = *options;
  auto output = RegionOutputOf(request.output());
  if (!output.ok()) return output.status();
  output_ = *output;
  if (output_ == v1::REGION_OUTPUT_STATES) {
    if (absl::Status s = CheckConfidence(request.confidence(), 0, 1, "confidence"); !s.ok()) return s;
  }
  confidence_ = request.confidence();
  time_ = request.time();
  blocks_.emplace(*box, kBlockCells);
  chunk_cells_ = ChunkCells(request.chunk_cells(), output_);
  chunks_per_block_ = (std::min(kBlockCells, box->cell_count()) + chunk_cells_ - 1) / chunk_cells_;
  return absl::OkStatus();
}

absl::Status RegionStream::Interrupted() const {
  const auto progress = [this] {
    return absl::StrCat(" after ", cells_sent_.load(), " of ", blocks_->box_cells(), " cells");
  };
  if (context_->IsCancelled()) return absl::CancelledError(absl::StrCat("PredictRegion cancelled", progress()));
  if (drain_->requested) {
    return absl::UnavailableError(
        absl::StrCat("fremend is shutting down: PredictRegion stopped", progress(), "; retry"));
  }
  if (std::chrono::system_clock::now() > context_->deadline()) {
    return absl::DeadlineExceededError(absl::StrCat("PredictRegion passed its deadline", progress()));
  }
  return absl::OkStatus();
}

void RegionStream::Pump() {
  Response* to_write = nullptr;
  std::optional<uint64_t> to_compute;
  std::optional<absl::Status> to_finish;
  {
    base::MutexLock lock(&mutex_);
    if (finished_) return;
    if (error_.ok()) error_ = Interrupted();
    const bool all_sent = next_block_ == blocks_->chunk_count() && ready_.empty();
    if (!error_.ok() || all_sent) {
      if (!writing_ && !computing_) {
        finished_ = true;
        to_finish = error_;
      }
    } else {
      if (!writing_ && !ready_.empty()) {
        writing_ = true;
        in_flight_ = std::move(ready_.front());
        ready_.pop_front();
        to_write = in_flight_.get();
      }
      // The next block while this one's chunks go out, unless a whole block's chunks still wait.
      if (!computing_ && next_block_ < blocks_->chunk_count() && ready_.size() < chunks_per_block_) {
        computing_ = true;
        to_compute = next_block_++;
      }
    }
  }
  if (to_write != nullptr) StartWrite(to_write);
  if (to_finish) FinishWith(*to_finish);
  if (!to_compute) return;
  if (blocks_->chunk(*to_compute).box.cell_count() <= kInlineCells) {
    Compute(*to_compute);
    return;
  }
  if (!deps_.blocking->Post([this, i = *to_compute] { Compute(i); })) {
    {
      base::MutexLock lock(&mutex_);
      computing_ = false;
      error_ = absl::ResourceExhaustedError("fremend is busy (too many calls waiting); retry PredictRegion later");
    }
    Pump();
  }
}

std::unique_ptr<v1::PredictRegionResponse> RegionStream::TakeBuffer() {
  {
    base::MutexLock lock(&mutex_);
    if (!free_.empty()) {
      std::unique_ptr<Response> buffer = std::move(free_.back());
      free_.pop_back();
      return buffer;
    }
  }
  return std::make_unique<Response>();
}

void RegionStream::Compute(uint64_t i) {
  // Skip the work when the client has gone meanwhile (the pool may have queued the block a while).
  absl::Status status = Interrupted();
  std::vector<std::unique_ptr<Response>> chunks;
  if (status.ok()) {
    const RegionPlan::Chunk block = blocks_->chunk(i);
    status = map_->PredictBox(block.box, time_, options_, scratch_);
    // A block is a run of the box's cells in the box's order, and so is each chunk of the block.
    const RegionPlan plan(block.box, chunk_cells_);
    for (uint64_t j = 0; status.ok() && j < plan.chunk_count(); ++j) {
      const RegionPlan::Chunk chunk = plan.chunk(j);
      std::unique_ptr<Response> buffer = TakeBuffer();
      buffer->set_offset(block.offset + chunk.offset);
      buffer->set_box_cells(blocks_->box_cells());
      EncodeRegionValues(output_, confidence_,
                         std::span<const float>(scratch_).subspan(chunk.offset, chunk.box.cell_count()), *buffer);
      chunks.push_back(std::move(buffer));
    }
  }
  {
    base::MutexLock lock(&mutex_);
    computing_ = false;
    if (!status.ok() && error_.ok()) error_ = status;
    for (auto& chunk : chunks) ready_.push_back(std::move(chunk));
  }
  Pump();
}

void RegionStream::OnWriteDone(bool ok) {
  {
    base::MutexLock lock(&mutex_);
    writing_ = false;
    cells_sent_ += in_flight_->float_values_size() + in_flight_->bytes_values().size();
    free_.push_back(std::move(in_flight_));
    if (!ok && error_.ok()) error_ = absl::CancelledError("PredictRegion: the client went away");
  }
  Pump();
}

void RegionStream::OnCancel() { Pump(); }

void RegionStream::FinishWith(const absl::Status& status) {
  const grpc::Status converted = ToGrpcStatus(status);
  record_.Finish(converted, absl::StrCat("cells=", cells_sent_.load(), "/", blocks_ ? blocks_->box_cells() : 0));
  Finish(converted);
}

void RegionStream::OnDone() {
  if (stream_id_) deps_.calls->EndStream(*stream_id_);
  delete this;
}

}  // namespace fremen::server
