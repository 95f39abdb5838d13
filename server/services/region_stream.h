// PredictRegion: a box of a grid at one time, streamed to the client in chunks
// (server/services/region_plan.h), as a server-streaming reactor.
//
// The box is computed a block at a time (up to 256k cells: one MapStore::PredictBox call, which
// spreads it over the map's shards), off the gRPC threads — on the blocking pool, or inline when
// the block is small — and each block is cut into chunks of at most 1 MiB, the messages. The next
// block is computed while the previous one's chunks are on the wire, and waits while a whole
// block's chunks do, so memory stays bounded (a few MiB) whatever the size of the box.
// Between chunks the stream checks for cancellation and its deadline and stops there (a huge box
// does not run on after the client has given up), and when the daemon drains for shutdown
// (UNAVAILABLE, which clients retry). Like ServeUnary, the call is counted in the CallTracker,
// authorized, and logged once finished.
//
// Thread-safety: reactions (gRPC threads) and block computations (pool threads) meet under one
// mutex; at most one computation and one write are in flight; Finish is called once, when neither
// is, so that nothing touches the reactor after OnDone deletes it.
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
#include "fremen/v1/query.pb.h"
#include "server/rpc/access_log.h"
#include "server/services/region_plan.h"
#include "server/rpc/unary_call.h"
#include "storage/map_store.h"

namespace fremen::server {

class RegionStream final : public grpc::ServerWriteReactor<v1::PredictRegionResponse> {
 public:
  // Starts the call; the reactor deletes itself once the call is done.
  static RegionStream* Start(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                             const v1::PredictRegionRequest& request);

  void OnWriteDone(bool ok) override ABSL_LOCKS_EXCLUDED(mutex_);
  void OnCancel() override ABSL_LOCKS_EXCLUDED(mutex_);
  void OnDone() override;

 private:
  using Response = v1::PredictRegionResponse;

  RegionStream(const ServiceDeps& deps, grpc::CallbackServerContext* context);
  // Checks the request and plans the chunks.
  absl::Status Prepare(const v1::PredictRegionRequest& request);
  // Decides, under the mutex, what comes next — a write, a computation, or the end — and does it.
  void Pump() ABSL_LOCKS_EXCLUDED(mutex_);
  // Computes block i and queues its chunks, then pumps.
  void Compute(uint64_t i) ABSL_LOCKS_EXCLUDED(mutex_);
  std::unique_ptr<Response> TakeBuffer() ABSL_LOCKS_EXCLUDED(mutex_);
  // Why the stream must stop now (cancelled, past its deadline), or OK.
  absl::Status Interrupted() const;
  void FinishWith(const absl::Status& status);

  const ServiceDeps deps_;
  grpc::CallbackServerContext* const context_;
  const CallRecord record_;
  // Set by the tracker when the daemon drains. Shared, so that the tracker may hold it past OnDone.
  struct DrainFlag final : CallTracker::Drainable {
    std::atomic<bool> requested{false};
    void WindDown() override { requested = true; }
  };
  const std::shared_ptr<DrainFlag> drain_ = std::make_shared<DrainFlag>();
  std::optional<uint64_t> stream_id_;  // BeginStream succeeded: EndStream in OnDone

  // Fixed by Prepare.
  std::shared_ptr<storage::MapStore> map_;
  std::optional<RegionPlan> blocks_;  // of the box
  uint64_t chunk_cells_ = 0;          // per message
  uint64_t chunks_per_block_ = 0;     // at most; the next block waits while this many do
  storage::PredictOptions options_;
  double time_ = 0;
  v1::RegionOutput output_ = v1::REGION_OUTPUT_FLOAT;
  float confidence_ = 0.5f;

  std::vector<float> scratch_;  // the computing thread's (one at a time)

  base::Mutex mutex_;
  absl::Status error_ ABSL_GUARDED_BY(mutex_);
  uint64_t next_block_ ABSL_GUARDED_BY(mutex_) = 0;  // the next to compute
  std::atomic<uint64_t> cells_sent_{0};  // read by Interrupted() outside the mutex
  bool computing_ ABSL_GUARDED_BY(mutex_) = false;
  bool writing_ ABSL_GUARDED_BY(mutex_) = false;
  bool finished_ ABSL_GUARDED_BY(mutex_) = false;
  // Chunks computed, in order, not yet written.
  std::deque<std::unique_ptr<Response>> ready_ ABSL_GUARDED_BY(mutex_);
  std::unique_ptr<Response> in_flight_ ABSL_GUARDED_BY(mutex_);
  std::vector<std::unique_ptr<Response>> free_ ABSL_GUARDED_BY(mutex_);
};

}  // namespace fremen::server
