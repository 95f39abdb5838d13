// The access log: one line per RPC on the "access" logger, written when the call finishes:
//   CreateMap ipv4:127.0.0.1:40312 OK 1.42ms
//   GetMap ipv4:127.0.0.1:40312 NOT_FOUND 0.08ms no map named "lab"
//   Ingest ipv4:127.0.0.1:40318 UNAVAILABLE 8120.55ms batches=812 observations=8120000 rejected=0 fremend is shutting down
// Finish also tells the call's end to the daemon's CallObserver (server/rpc/call_observer.h), when
// there is one: every call, unary or streaming, ends here.
// Thread-safety: a CallRecord belongs to one call; Finish may run on any thread.
#pragma once

#include <grpcpp/server_context.h>
#include <grpcpp/support/status.h>

#include <string>

#include "absl/strings/string_view.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "server/rpc/call_observer.h"

namespace fremen::server {

// The name of the access logger, for server/rpc/logging.h.
inline constexpr char kAccessLogger[] = "access";

class CallRecord {
 public:
  // Starts the clock of a call to `method` from the context's peer. `observer` (may be null)
  // must outlive the call.
  CallRecord(absl::string_view method, const grpc::ServerContextBase& context, CallObserver* observer = nullptr)
      : method_(method), peer_(context.peer()), start_(absl::Now()), observer_(observer) {}

  // Logs the call's line; `details` (what a stream carried) follows the duration.
  void Finish(const grpc::Status& status, absl::string_view details = {}) const;

 private:
  absl::string_view method_;  // a literal of the service's method table
  std::string peer_;
  absl::Time start_;
  CallObserver* observer_;
};

}  // namespace fremen::server
