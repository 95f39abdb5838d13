// A robot's ingest session: scans sent over IngestService.Ingest (one bidirectional stream) and
// acknowledged once durable, surviving daemon restarts and link drops without losing or
// duplicating a batch.
//
// How: every batch gets (writer_id, sequence) — sequences increase by one per Send — and stays in
// the session until the daemon acknowledges it. When the stream breaks with UNAVAILABLE (daemon
// restarting or gone, link lost), the session opens a new stream with exponential backoff and
// resends every unacknowledged batch in order, unchanged; the daemon answers a batch it had
// already applied with duplicate = true and does not apply it again (it remembers the content of
// each writer's recent sequences, storage/dedup_table.h). So each batch is applied exactly once.
//
// - Send blocks while max_unacknowledged batches await their ack (backpressure: memory stays
//   bounded while the daemon is away), and returns the batch's sequence.
// - Flush blocks until every batch sent so far is acknowledged.
// - Acks (accepted/rejected counts, the first rejections with their reasons, or the batch's error
//   when it was refused as a whole) arrive in sequence order: through TakeAcks, totals(), and the
//   optional on_ack callback.
// - An error that retrying cannot fix (unknown map, bad token, a store that refuses writes) or
//   reconnecting for longer than reconnect_timeout ends the session: Send, Flush and Close return
//   it from then on; unacknowledged() tells how many batches were not applied for sure.
// - A writer_id used before (a robot that rebooted and lost its count): with first_sequence 0, the
//   default, the session asks the daemon (IngestService.LastSequence) and starts after the
//   writer's last sequence, so that nothing new is taken for a retry. A batch sent under a
//   sequence the writer already used for other content is refused, never dropped silently: its
//   ack's error is ALREADY_EXISTS, naming the sequence to continue after.
// - An unparsable message (a corrupted link) ends the session with the daemon's INVALID_ARGUMENT,
//   which names the message's position in the stream.
//
// Thread-safety: Send, Flush, Close, TakeAcks and the accessors may be called from any threads; a
// background thread reads acks and reconnects. on_ack runs on that thread: it must not block or
// call into the session.
#pragma once

#include <grpcpp/grpcpp.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "base/mutex.h"
#include "client/lib/connection.h"
#include "client/lib/scan_builder.h"

#include "fremen/v1/ingest.grpc.pb.h"

namespace fremen::client {

struct Rejection {
  // Position of the observation in the scan (for a patch: the offset, x fastest).
  uint32_t index = 0;
  v1::RejectReason reason = v1::REJECT_REASON_UNSPECIFIED;
};

// The daemon's answer to one batch.
struct IngestAck {
  uint64_t sequence = 0;
  uint64_t accepted = 0;
  uint64_t rejected = 0;
  // Applied before (the batch was resent after a reconnect); nothing applied this time.
  bool duplicate = false;
  // The first rejections (at most 16).
  std::vector<Rejection> rejections;
  // Not OK when the batch was refused as a whole (nothing of it applied): the code and the daemon's
  // message naming the field at fault. Such a batch is not resent.
  absl::Status error;
};

struct IngestTotals {
  uint64_t sent = 0;          // batches given to Send
  uint64_t acknowledged = 0;  // batches answered (including duplicates and refused ones)
  uint64_t duplicates = 0;
  uint64_t refused = 0;     // batches with an error
  uint64_t accepted = 0;    // observations
  uint64_t rejected = 0;    // observations
  uint64_t reconnects = 0;  // streams opened after the first
};

struct IngestOptions {
  // Who writes; 0 = a random id for this session.
  uint64_t writer_id = 0;
  // The first batch's sequence; 0: one above the writer's last sequence in the map (asked at Open
  // when writer_id is set; 1 for a random writer, which is new). Default: 0.
  uint64_t first_sequence = 0;
  // Batches sent but not yet acknowledged before Send blocks. Bounds memory and what a reconnect
  // resends; the daemon recognises a resent batch among a writer's last 256 sequences, so keep it
  // at most that. REQUIRES: ≥ 1. Default: 64.
  size_t max_unacknowledged = 64;
  // Give up when no stream has worked for this long (InfiniteDuration: never). Default: 5 min.
  absl::Duration reconnect_timeout = absl::Minutes(5);
  // Keep acks for TakeAcks (turn off when only totals() or on_ack are used, so they do not pile
  // up). Default: true.
  bool collect_acks = true;
  // Called for every ack, in sequence order, on the session's thread.
  std::function<void(const IngestAck&)> on_ack;
};

class IngestSession {
 public:
  // Checks that `map` exists (NOT_FOUND otherwise, with the daemon's message), learns where the
  // writer continues (see first_sequence) and starts the session. The stream itself opens with the
  // first batch.
  static absl::StatusOr<std::unique_ptr<IngestSession>> Open(std::shared_ptr<Connection> connection, std::string map,
                                                             IngestOptions options = {});
  // Stops at once: batches not yet acknowledged are abandoned (call Close first to wait for them).
  ~IngestSession() ABSL_LOCKS_EXCLUDED(mutex_);
  IngestSession(const IngestSession&) = delete;
  IngestSession& operator=(const IngestSession&) = delete;

  // Queues the scan for sending and returns its sequence; blocks while max_unacknowledged batches
  // await their acks. The session's error once it has ended.
  absl::StatusOr<uint64_t> Send(Scan scan) ABSL_LOCKS_EXCLUDED(write_mutex_, mutex_);
  // Waits until every batch sent so far is acknowledged (DEADLINE_EXCEEDED after `timeout`,
  // naming how many are not), or the session's error.
  absl::Status Flush(absl::Duration timeout = absl::InfiniteDuration()) ABSL_LOCKS_EXCLUDED(mutex_);
  // Flush, then ends the stream and the session's thread. Send fails afterwards.
  absl::Status Close(absl::Duration timeout = absl::InfiniteDuration()) ABSL_LOCKS_EXCLUDED(write_mutex_, mutex_);

  // The acks received since the last call, in sequence order (with collect_acks).
  std::vector<IngestAck> TakeAcks() ABSL_LOCKS_EXCLUDED(mutex_);
  IngestTotals totals() const ABSL_LOCKS_EXCLUDED(mutex_);
  // Batches sent but not acknowledged.
  size_t unacknowledged() const ABSL_LOCKS_EXCLUDED(mutex_);
  uint64_t writer_id() const { return writer_id_; }
  // The sequence the first Send got (or gets).
  uint64_t first_sequence() const { return first_sequence_; }
  const std::string& map() const { return map_; }

 private:
  struct Pending {
    uint64_t sequence;
    std::shared_ptr<const v1::IngestRequest> request;
    uint64_t sent_on = 0;  // the stream generation it was last written on; 0 = never
  };
  struct Stream {
    std::unique_ptr<grpc::ClientContext> context;
    std::unique_ptr<grpc::ClientReaderWriter<v1::IngestRequest, v1::IngestResponse>> rw;
  };

  IngestSession(std::shared_ptr<Connection> connection, std::string map, IngestOptions options, uint64_t writer_id,
                uint64_t first_sequence);

  // The background thread: opens streams, reads acks, reconnects.
  void Run() ABSL_LOCKS_EXCLUDED(write_mutex_, mutex_);
  // Opens a stream and writes every pending batch on it.
  std::shared_ptr<Stream> OpenStreamLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(write_mutex_) ABSL_LOCKS_EXCLUDED(mutex_);
  // Writes, in order, the pending batches not yet written on the current stream. Stops at a failed
  // write (the reader notices the broken stream).
  void WriteUnsentLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(write_mutex_) ABSL_LOCKS_EXCLUDED(mutex_);
  // The ack of the oldest pending batch from `response`; INTERNAL when it answers another batch.
  absl::Status MatchLocked(const v1::IngestResponse& response, IngestAck& ack) const
      ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // The oldest pending batch is acknowledged: drop it, count it, keep the ack.
  void RecordLocked(IngestAck ack) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Ends the session with `error`.
  void FailLocked(absl::Status error) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);

  const std::shared_ptr<Connection> connection_;
  const std::string map_;
  const IngestOptions options_;
  const uint64_t writer_id_;
  const uint64_t first_sequence_;

  // Held while writing to the stream and while replacing it; taken before mutex_, never after
  // (ABSL_ACQUIRED_BEFORE says so, though clang 14 does not check it). Timed: the reader waits for
  // a writer only so long before cancelling the call that blocks it.
  base::TimedMutex write_mutex_ ABSL_ACQUIRED_BEFORE(mutex_);
  // Written with both mutexes held, read with either: a rule the analysis cannot express (its
  // ABSL_GUARDED_BY takes one mutex for reads and writes alike), so these two are not annotated.
  std::shared_ptr<Stream> stream_;
  uint64_t generation_ = 0;

  mutable base::Mutex mutex_;
  base::CondVar changed_;
  std::deque<Pending> pending_ ABSL_GUARDED_BY(mutex_);
  uint64_t next_sequence_ ABSL_GUARDED_BY(mutex_);
  std::vector<IngestAck> acks_ ABSL_GUARDED_BY(mutex_);
  IngestTotals totals_ ABSL_GUARDED_BY(mutex_);
  absl::Status error_ ABSL_GUARDED_BY(mutex_);     // the session has ended with this
  bool closing_ ABSL_GUARDED_BY(mutex_) = false;   // Close: no more Send
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;  // destructor: leave now

  std::thread thread_;
};

}  // namespace fremen::client
