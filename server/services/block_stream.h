// BlockStream: the machinery of a server-streaming query whose answer is computed a block at a time
// off the gRPC threads and sent as chunks of at most 1 MiB (PredictRegion, PredictRegionSeries).
//
// A subclass plans its blocks in Prepare and computes block i into its chunks in ComputeBlock; a
// block runs on the blocking pool, or inline when the subclass says it is small. The next block is
// computed while the previous one's chunks are on the wire, and waits while a whole block's chunks
// do, so memory stays bounded whatever the size of the answer. Between chunks the stream checks
// for cancellation and its deadline and stops there (a huge answer does not run on after the
// client has given up), and when the daemon drains for shutdown (UNAVAILABLE, which clients retry).
// Like ServeUnary, the call is counted in the CallTracker, authorized, and logged once finished.
//
// The methods are raw (the service registers them with WithRawCallbackMethod_): the stream parses
// its request and writes its chunks as serialized messages (server/services/wire_chunk.h), so that
// a subclass may write a chunk's values where they go on the wire.
//
// Thread-safety: reactions (gRPC threads) and block computations (pool threads) meet under one
// mutex; at most one computation and one write are in flight; Finish is called once, when neither
// is, so that nothing touches the reactor after OnDone deletes it. ComputeBlock calls are one at a
// time, in block order, each seeing what the previous ones wrote.
#pragma once

#include <grpcpp/server_context.h>
#include <grpcpp/support/server_callback.h>

#include <atomic>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "base/mutex.h"
#include "server/rpc/access_log.h"
#include "server/rpc/unary_call.h"
#include "server/services/wire_chunk.h"

// Instantiated in block_stream.cc for the requests and responses of QueryService's streams.

namespace fremen::server {

template <typename RequestT, typename ResponseT>
class BlockStream : public grpc::ServerWriteReactor<grpc::ByteBuffer> {
 public:
  using Request = RequestT;
  using Response = ResponseT;

  void OnWriteDone(bool ok) override ABSL_LOCKS_EXCLUDED(mutex_);
  void OnCancel() override ABSL_LOCKS_EXCLUDED(mutex_) { Pump(); }
  void OnDone() override;

 protected:
  using Chunks = std::vector<WireChunk>;

  BlockStream(const ServiceDeps& deps, grpc::CallbackServerContext* context, const MethodSpec& method)
      : deps_(deps), context_(context), method_(method), record_(method.name, *context, deps.observer) {}
  virtual ~BlockStream() = default;

  // Starts the call: counted, authorized, its request parsed (INVALID_ARGUMENT if it does not
  // parse) and prepared (the subclass's checks and plan), then streamed or finished with the first
  // error. The stream deletes itself once the call is done.
  void Begin(const grpc::ByteBuffer& raw_request);

  // The subclass's part. Prepare checks the request and plans: it sets the blocks known so far
  // (SetBlocks) and the values the whole answer holds (set_total_values).
  virtual absl::Status Prepare(const Request& request) = 0;
  // Computes block i into its chunks, in stream order (AddChunk, or ValuesInPlace); `more_blocks`: the
  // blocks it adds after the known ones (a plan that knows its size only once computed).
  virtual absl::Status ComputeBlock(uint64_t i, Chunks& chunks, uint64_t& more_blocks) = 0;
  // Whether block i is so small that the hop to the pool would cost more than the work.
  virtual bool ComputesInline(uint64_t i) const = 0;

  // Before the first block: `count` blocks, of at most `chunks_per_block` chunks each.
  void SetBlocks(uint64_t count, uint64_t chunks_per_block) ABSL_NO_THREAD_SAFETY_ANALYSIS {
    block_count_ = count;
    chunks_per_block_ = chunks_per_block;
  }
  void set_total_values(uint64_t total) { total_values_ = total; }
  // Appends `response`, serialized, to `chunks`.
  static absl::Status AddChunk(const Response& response, Chunks& chunks) {
    absl::StatusOr<WireChunk> chunk =
        SerializedChunk(response, response.float_values_size() + response.bytes_values().size());
    if (!chunk.ok()) return chunk.status();
    chunks.push_back(*std::move(chunk));
    return absl::OkStatus();
  }

  const ServiceDeps deps_;
  grpc::CallbackServerContext* const context_;

 private:
  // Decides, under the mutex, what comes next — a write, a computation, or the end — and does it.
  void Pump() ABSL_LOCKS_EXCLUDED(mutex_);
  // Computes block i and queues its chunks, then pumps.
  void Compute(uint64_t i) ABSL_LOCKS_EXCLUDED(mutex_);
  // Why the stream must stop now (cancelled, past its deadline, draining), or OK.
  absl::Status Interrupted() const;
  void FinishWith(const absl::Status& status);

  const MethodSpec method_;
  const CallRecord record_;
  // Set by the tracker when the daemon drains. Shared, so that the tracker may hold it past OnDone.
  struct DrainFlag final : CallTracker::Drainable {
    std::atomic<bool> requested{false};
    void WindDown() override { requested = true; }
  };
  const std::shared_ptr<DrainFlag> drain_ = std::make_shared<DrainFlag>();
  std::optional<uint64_t> stream_id_;  // BeginStream succeeded: EndStream in OnDone
  std::atomic<uint64_t> total_values_{0};
  std::atomic<uint64_t> values_sent_{0};  // read by Interrupted() outside the mutex

  base::Mutex mutex_;
  absl::Status error_ ABSL_GUARDED_BY(mutex_);
  uint64_t block_count_ ABSL_GUARDED_BY(mutex_) = 0;
  uint64_t chunks_per_block_ ABSL_GUARDED_BY(mutex_) = 1;  // the next block waits while this many do
  uint64_t next_block_ ABSL_GUARDED_BY(mutex_) = 0;  // the next to compute
  bool computing_ ABSL_GUARDED_BY(mutex_) = false;
  bool writing_ ABSL_GUARDED_BY(mutex_) = false;
  bool finished_ ABSL_GUARDED_BY(mutex_) = false;
  // Chunks computed, in order, not yet written.
  std::deque<WireChunk> ready_ ABSL_GUARDED_BY(mutex_);
  WireChunk in_flight_ ABSL_GUARDED_BY(mutex_);
};

}  // namespace fremen::server
