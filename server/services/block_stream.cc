#include "server/services/block_stream.h"

#include <grpcpp/impl/codegen/proto_utils.h>

#include <chrono>

#include "absl/strings/str_cat.h"
#include "fremen/v1/query.pb.h"

namespace fremen::server {

template <typename RequestT, typename ResponseT>
void BlockStream<RequestT, ResponseT>::Begin(const grpc::ByteBuffer& raw_request) {
  absl::StatusOr<uint64_t> id = deps_.calls->BeginStream(drain_);
  absl::Status status = id.status();
  if (id.ok()) stream_id_ = *id;
  if (status.ok()) status = deps_.auth->Authorize(*context_, method_.access, method_.name);
  Request request;
  if (status.ok()) {
    grpc::ByteBuffer buffer(raw_request);  // shares the slices; the parse consumes the copy
    if (!grpc::SerializationTraits<Request>::Deserialize(&buffer, &request).ok()) {
      status = absl::InvalidArgumentError(
          absl::StrCat(method_.name, ": cannot parse the request as ", request.GetTypeName()));
    }
  }
  if (status.ok()) status = Prepare(request);
  if (!status.ok()) {
    {
      base::MutexLock lock(&mutex_);  // OnCancel may already pump
      finished_ = true;
    }
    FinishWith(status);
    return;
  }
  Pump();
}

template <typename RequestT, typename ResponseT>
absl::Status BlockStream<RequestT, ResponseT>::Interrupted() const {
  const auto progress = [this] {
    return absl::StrCat(" after ", values_sent_.load(), " of ", total_values_.load(), " values");
  };
  if (context_->IsCancelled()) return absl::CancelledError(absl::StrCat(method_.name, " cancelled", progress()));
  if (drain_->requested) {
    return absl::UnavailableError(
        absl::StrCat("fremend is shutting down: ", method_.name, " stopped", progress(), "; retry"));
  }
  if (std::chrono::system_clock::now() > context_->deadline()) {
    return absl::DeadlineExceededError(absl::StrCat(method_.name, " passed its deadline", progress()));
  }
  return absl::OkStatus();
}

template <typename RequestT, typename ResponseT>
void BlockStream<RequestT, ResponseT>::Pump() {
  grpc::ByteBuffer* to_write = nullptr;
  std::optional<uint64_t> to_compute;
  std::optional<absl::Status> to_finish;
  {
    base::MutexLock lock(&mutex_);
    if (finished_) return;
    if (error_.ok()) error_ = Interrupted();
    // A block being computed may add blocks: not all sent until it is done.
    const bool all_sent = next_block_ == block_count_ && ready_.empty() && !computing_;
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
        to_write = &in_flight_.bytes;
      }
      // The next block while this one's chunks go out, unless a whole block's chunks still wait.
      if (!computing_ && next_block_ < block_count_ && ready_.size() < chunks_per_block_) {
        computing_ = true;
        to_compute = next_block_++;
      }
    }
  }
  if (to_write != nullptr) this->StartWrite(to_write);
  if (to_finish) FinishWith(*to_finish);
  if (!to_compute) return;
  if (ComputesInline(*to_compute)) {
    Compute(*to_compute);
    return;
  }
  if (!deps_.blocking->Post([this, i = *to_compute] { Compute(i); })) {
    {
      base::MutexLock lock(&mutex_);
      computing_ = false;
      error_ = absl::ResourceExhaustedError(
          absl::StrCat("fremend is busy (too many calls waiting); retry ", method_.name, " later"));
    }
    Pump();
  }
}

template <typename RequestT, typename ResponseT>
void BlockStream<RequestT, ResponseT>::Compute(uint64_t i) {
  // Skip the work when the client has gone meanwhile (the pool may have queued the block a while).
  absl::Status status = Interrupted();
  Chunks chunks;
  uint64_t more_blocks = 0;
  if (status.ok()) status = ComputeBlock(i, chunks, more_blocks);
  {
    base::MutexLock lock(&mutex_);
    computing_ = false;
    block_count_ += more_blocks;
    if (!status.ok() && error_.ok()) error_ = status;
    for (auto& chunk : chunks) ready_.push_back(std::move(chunk));
  }
  Pump();
}

template <typename RequestT, typename ResponseT>
void BlockStream<RequestT, ResponseT>::OnWriteDone(bool ok) {
  {
    base::MutexLock lock(&mutex_);
    writing_ = false;
    values_sent_ += in_flight_.values;
    in_flight_ = WireChunk();  // its buffer's memory back now, not at the next write
    if (!ok && error_.ok()) error_ = absl::CancelledError(absl::StrCat(method_.name, ": the client went away"));
  }
  Pump();
}

template <typename RequestT, typename ResponseT>
void BlockStream<RequestT, ResponseT>::FinishWith(const absl::Status& status) {
  const grpc::Status converted = ToGrpcStatus(status);
  record_.Finish(converted, absl::StrCat("values=", values_sent_.load(), "/", total_values_.load()));
  this->Finish(converted);
}

template <typename RequestT, typename ResponseT>
void BlockStream<RequestT, ResponseT>::OnDone() {
  if (stream_id_) deps_.calls->EndStream(*stream_id_);
  delete this;
}

template class BlockStream<v1::PredictRegionRequest, v1::PredictRegionResponse>;
template class BlockStream<v1::PredictRegionSeriesRequest, v1::PredictRegionSeriesResponse>;

}  // namespace fremen::server
