// WindowedIngest: one Ingest stream of the load generators (fremen_ingest_load, fremen_office_load),
// keeping up to `window` batches unacknowledged, on gRPC's callback API.
//
// Why the callback API: the synchronous stream (a writer thread blocked in Write, a reader thread
// blocked in Read) hands every message from a gRPC thread to the caller's and back, about six
// futex calls per batch. With small batches that handoff cost the client about as much CPU as the
// daemon spent ingesting, on the same two cores (docs/performance.md, "Small scans"). Here the
// next batch is written from the reaction that made room for it, on gRPC's thread, without a
// handoff.
//
// Thread-safety: `next` and `on_ack` run on gRPC's threads, one at a time for `next` (a write
// starts only after the previous one is done) but possibly concurrently with `on_ack`. Stop and
// Await may be called from any thread.
#pragma once

#include <grpcpp/grpcpp.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>

#include "fremen/v1/ingest.grpc.pb.h"

namespace fremen::bench {

class WindowedIngest final : public grpc::ClientBidiReactor<v1::IngestRequest, v1::IngestResponse> {
 public:
  // Batch `sequence` (0, 1, ...), or nullptr when there are no more: the stream then ends once the
  // batches written are acknowledged. The request must stay as it is until `next` is called again
  // (it is being written until then).
  using NextBatch = std::function<const v1::IngestRequest*(uint64_t sequence)>;
  using OnAck = std::function<void(const v1::IngestResponse& ack)>;

  // Opens the stream on `stub` and starts writing. `stub` must outlive the call.
  WindowedIngest(v1::IngestService::Stub& stub, std::unique_ptr<grpc::ClientContext> context, int window,
                 NextBatch next, OnAck on_ack);
  WindowedIngest(const WindowedIngest&) = delete;
  WindowedIngest& operator=(const WindowedIngest&) = delete;
  // Waits for the call to end (a reactor must outlive its call).
  ~WindowedIngest() override;

  // Writes no more batches: the stream ends once the ones written are acknowledged.
  void Stop();
  // Waits until the call has ended; its status (OK once every batch written was answered).
  grpc::Status Await();
  // Whether the call has ended (Await would not wait).
  bool Ended();

  void OnWriteDone(bool ok) override;
  void OnReadDone(bool ok) override;
  void OnDone(const grpc::Status& status) override;

 private:
  // Starts the next write, or the end of the writes, when one may start now.
  void PumpLocked();

  const std::unique_ptr<grpc::ClientContext> context_;
  const int window_;
  const NextBatch next_;
  const OnAck on_ack_;
  v1::IngestResponse ack_;  // the read in flight's

  std::mutex mutex_;
  std::condition_variable done_changed_;
  uint64_t sequence_ = 0;     // of the next batch
  int unacknowledged_ = 0;    // written (or being written), not yet answered
  bool writing_ = false;      // a StartWrite is outstanding
  bool stopping_ = false;     // no more batches: end the writes
  bool writes_ended_ = false;  // StartWritesDone was called, or a write failed
  bool done_ = false;
  grpc::Status status_;
};

}  // namespace fremen::bench
