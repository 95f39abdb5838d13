// What the RPC layer tells an observer, for the daemon's metrics (server/metrics/), so that
// server/rpc depends on no metrics library: every call's end (unary and streaming alike, from
// CallRecord::Finish, the one place every call ends), and what only the ingest stream sees — the
// bytes of the batches it reads and the time it waits for room in a map's queue.
//
// Thread-safety: called from gRPC's, the blocking pool's and the store's threads at once; an
// implementation counts and returns (it is on every call's path).
#pragma once

#include <grpcpp/support/status.h>

#include <cstdint>
#include <string>

#include "absl/strings/string_view.h"
#include "absl/time/time.h"

namespace fremen::server {

class CallObserver {
 public:
  virtual ~CallObserver() = default;
  // A call of `method` (its name in the method table: "GetMap", "Ingest") ended with `code`,
  // `took` after it started.
  virtual void CallFinished(absl::string_view method, grpc::StatusCode code, absl::Duration took) = 0;
  // The ingest stream read a message of `bytes` for `map`.
  virtual void IngestReceived(const std::string& map, uint64_t bytes) = 0;
  // An ingest stream waited `took` for room in `map`'s queue (backpressure) before resubmitting.
  virtual void IngestWaited(const std::string& map, absl::Duration took) = 0;
};

}  // namespace fremen::server
