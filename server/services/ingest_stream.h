// One fremen.v1.IngestService.Ingest call: a bidirectional stream of batches in, one IngestResponse
// out per batch, in batch order, each once the store says the batch is durable and applied.
//
// Flow: OnReadDone parses the message (the stream reads raw bytes, so that an unparsable message
// is told from the client's end of the stream), converts the request (server/convert/ingest_convert.h) and
// hands it to MapStore::Submit, whose callback (on a store thread) fills the batch's slot; slots
// are written in order, one StartWrite at a time.
// - Backpressure: at most kMaxUnanswered batches are read but not yet answered; beyond that the
//   stream stops reading (no StartRead) until a response is written, so gRPC flow control slows
//   the client down. When the store's queue is full (Submit: ResourceExhausted) the request is
//   held, reading stops, and MapStore::OnRoom resubmits it — no polling, no unbounded buffer.
//   Only that refusal (storage::IsQueueFull) is waited out: a map whose storage failed refuses
//   with its error (ResourceExhausted for a full disk, too), which ends the stream at once.
// - Errors: a batch unusable as a whole, or whose sequence the writer used for another batch, gets
//   a response with `error` and the stream goes on; an unparsable message (INVALID_ARGUMENT
//   naming its position), an unknown map (NOT_FOUND), another map than the first request's
//   (INVALID_ARGUMENT) or a store that fails ends the stream once the earlier batches are
//   answered.
// - Shutdown (CallTracker::Drain → WindDown): reading stops, the batches in the store are answered,
//   then the stream ends with UNAVAILABLE; a batch read but not submitted is dropped unanswered
//   (the client resends what was not acknowledged; the store recognises repeats).
// - Cancellation: the stream finishes at once; batches already submitted still complete in the
//   store, their acknowledgements are dropped.
// Lifetime: owned by shared pointers — its own until OnDone, and one in each store callback — so
// that it outlives both gRPC's last reaction and the store's last callback.
//
// Thread-safety: reactions (gRPC threads), store callbacks (store threads) and WindDown (the
// draining thread) meet under one mutex, under which the gRPC operations are also started (they
// never run a reaction inline for this reactor); StartRead, StartWrite and Finish are each
// started at most once at a time, and nothing after Finish.
#pragma once

#include <grpcpp/impl/codegen/proto_utils.h>
#include <grpcpp/server_context.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/server_callback.h>

#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "absl/time/time.h"
#include "fremen/v1/ingest.pb.h"
#include "server/rpc/access_log.h"
#include "server/rpc/call_tracker.h"
#include "server/rpc/unary_call.h"
#include "storage/batch.h"
#include "storage/map_store.h"

namespace fremen::server {

class IngestStream final : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>,
                           public CallTracker::Drainable,
                           public std::enable_shared_from_this<IngestStream> {
 public:
  // Batches read but not yet answered, per stream: the window the C++ and Python clients keep by
  // default (max_unacknowledged, max_in_flight), so that their batches wait in the store's group
  // commit, not in HTTP/2 flow control. At 8, 1000-cell scans ran at 12-13k batches/s and a client
  // keeping 64 unanswered was slower than one keeping 8; at 64, 22-28k (docs/performance.md,
  // "The stream's window"). The memory it lets a stream hold is the responses' slots: the batches
  // themselves are in the store, whose queue is bounded (MapStore::Submit refuses past it).
  static constexpr size_t kMaxUnanswered = 64;

  // Starts the call; the reactor frees itself once the call is done and the store is done with it.
  static IngestStream* Start(const ServiceDeps& deps, grpc::CallbackServerContext* context);

  void OnReadDone(bool ok) override ABSL_LOCKS_EXCLUDED(mutex_);
  void OnWriteDone(bool ok) override ABSL_LOCKS_EXCLUDED(mutex_);
  void OnCancel() override ABSL_LOCKS_EXCLUDED(mutex_);
  void OnDone() override ABSL_LOCKS_EXCLUDED(mutex_);
  void WindDown() override ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  // One batch's place in the response order.
  struct Slot {
    bool ready = false;    // response holds the answer
    bool failed = false;   // the store failed the batch: the stream ends with `failure`
    absl::Status failure;
    v1::IngestResponse response;
    grpc::ByteBuffer bytes;  // response, serialized for its StartWrite
  };

  IngestStream(const ServiceDeps& deps, grpc::CallbackServerContext* context);

  // Parses the message read into request_; INVALID_ARGUMENT naming its position if it is not one.
  absl::Status Parse();
  // The map of request_: fixed by the first request, the same for every later one.
  absl::Status Route();
  // Converts and submits the held request (its slot: held_slot_). Called without the lock.
  void SubmitHeld() ABSL_LOCKS_EXCLUDED(mutex_);
  // After Submit refused the held request for lack of room: resubmit once there is room.
  void WaitForRoom(uint64_t observations) ABSL_LOCKS_EXCLUDED(mutex_);
  // The store has room again: resubmit, unless the stream is ending.
  void RoomAvailable() ABSL_LOCKS_EXCLUDED(mutex_);
  void OnAck(Slot& slot, absl::StatusOr<storage::BatchAck> ack) ABSL_LOCKS_EXCLUDED(mutex_);
  // Ends the stream with `status` once the batches in flight are answered (the first reason wins).
  void EndLocked(absl::Status status) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Starts what can start now — a write, the finish, a read.
  void PumpLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  void FinishLocked(const absl::Status& status) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  bool EndingLocked() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_) {
    return end_status_.has_value() || cancelled_ || finished_;
  }

  const ServiceDeps deps_;
  grpc::CallbackServerContext* const context_;
  const CallRecord record_;
  std::shared_ptr<IngestStream> self_;  // until OnDone
  std::optional<uint64_t> tracker_id_;  // set once the tracker counts the call

  // Written by the read path only (one read at a time, then the held request), before any
  // submission that uses them.
  std::shared_ptr<storage::MapStore> map_;
  std::string map_name_;
  grpc::ByteBuffer message_;   // gRPC's while reading_, the stream's while holding_
  v1::IngestRequest request_;  // parsed from message_; the stream's while holding_
  uint64_t messages_ = 0;      // read so far, for errors naming a message's position
  // The slot of request_ while holding_ (set under the mutex with the slot's creation).
  Slot* held_slot_ = nullptr;

  base::Mutex mutex_;
  // Unanswered batches, in order; references stay valid at both ends.
  std::deque<Slot> slots_ ABSL_GUARDED_BY(mutex_);
  bool reading_ ABSL_GUARDED_BY(mutex_) = false;       // a StartRead is outstanding
  bool holding_ ABSL_GUARDED_BY(mutex_) = false;       // request_ holds a batch not yet in the store
  bool waiting_room_ ABSL_GUARDED_BY(mutex_) = false;  // ... because the store's queue is full
  absl::Time waiting_since_ ABSL_GUARDED_BY(mutex_);    // ... from then (for the metrics)
  bool writing_ ABSL_GUARDED_BY(mutex_) = false;       // a StartWrite is outstanding (of slots_.front())
  bool cancelled_ ABSL_GUARDED_BY(mutex_) = false;
  bool finished_ ABSL_GUARDED_BY(mutex_) = false;
  std::optional<absl::Status> end_status_ ABSL_GUARDED_BY(mutex_);
  // For the access log.
  uint64_t answered_ ABSL_GUARDED_BY(mutex_) = 0;
  uint64_t accepted_ ABSL_GUARDED_BY(mutex_) = 0;
  uint64_t rejected_ ABSL_GUARDED_BY(mutex_) = 0;
};

}  // namespace fremen::server
