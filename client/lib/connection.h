// A connection to fremend: one gRPC channel with the options' credentials, keepalive and reconnect
// settings, the four services' stubs, and the two things every call needs — a client context with
// the deadline and the metadata (bearer token, x-fremen-map routing header), and the retry loop for
// idempotent calls on UNAVAILABLE.
//
// The channel connects lazily and reconnects by itself; a Connection is cheap to share
// (std::shared_ptr) between a Client and its IngestSessions.
// Thread-safety: thread-safe after Open (the stubs and channel are; the options are immutable).
#pragma once

#include <grpcpp/grpcpp.h>

#include <functional>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "client/lib/options.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"

namespace fremen::client {

class Connection {
 public:
  // Checks the options (INVALID_ARGUMENT naming the field) and creates the channel. Does not wait
  // for the daemon: the first call does.
  static absl::StatusOr<std::shared_ptr<Connection>> Open(ConnectionOptions options);

  const ConnectionOptions& options() const { return options_; }
  const std::string& address() const { return options_.address; }
  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }

  v1::MapService::Stub& maps() const { return *maps_; }
  v1::IngestService::Stub& ingest() const { return *ingest_; }
  v1::QueryService::Stub& query() const { return *query_; }
  v1::AdminService::Stub& admin() const { return *admin_; }

  // A context for one attempt: deadline (none when `deadline` is InfiniteFuture), the bearer token,
  // and x-fremen-map when `map` is not empty.
  std::unique_ptr<grpc::ClientContext> NewContext(absl::Time deadline, absl::string_view map = "") const;

  // The absolute deadline of a call made now with `call`.
  absl::Time DeadlineOf(const CallOptions& call) const;

  // Runs `attempt` (one gRPC call on the given context) until it succeeds, fails with a code that
  // is not retryable, or the deadline or retry policy is exhausted; sleeps the backoff between
  // attempts. Only for idempotent calls. The last attempt's status, converted (status.h).
  using Attempt = std::function<grpc::Status(grpc::ClientContext&)>;
  absl::Status CallIdempotent(const CallOptions& call, absl::string_view map, const Attempt& attempt) const;
  // One attempt, for calls that must not be repeated blindly (CreateMap, DeleteMap, backups).
  absl::Status CallOnce(const CallOptions& call, absl::string_view map, const Attempt& attempt) const;

 private:
  explicit Connection(ConnectionOptions options, std::shared_ptr<grpc::Channel> channel);
  // Sleeps `delay` before a retry of a call that failed with `failed`, connecting the channel meanwhile.
  void PauseBeforeRetry(const absl::Status& failed, absl::Duration delay) const;

  const ConnectionOptions options_;
  const std::shared_ptr<grpc::Channel> channel_;
  const std::unique_ptr<v1::MapService::Stub> maps_;
  const std::unique_ptr<v1::IngestService::Stub> ingest_;
  const std::unique_ptr<v1::QueryService::Stub> query_;
  const std::unique_ptr<v1::AdminService::Stub> admin_;
};

// A random 64-bit seed (for jitter and default writer ids).
uint64_t RandomSeed();

}  // namespace fremen::client
