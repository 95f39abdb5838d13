#include "client/lib/connection.h"

#include <random>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/lib/backoff.h"
#include "client/lib/status.h"

namespace fremen::client {

namespace {

int Milliseconds(absl::Duration d) { return static_cast<int>(absl::ToInt64Milliseconds(d)); }

absl::Status Validate(const ConnectionOptions& o) {
  if (o.address.empty()) return absl::InvalidArgumentError("address is empty: give fremend's host:port");
  if (o.tls_client_cert_pem.empty() != o.tls_client_key_pem.empty()) {
    return absl::InvalidArgumentError("tls_client_cert_pem and tls_client_key_pem: give both or neither");
  }
  if (o.default_timeout <= absl::ZeroDuration()) {
    return absl::InvalidArgumentError("default_timeout must be positive");
  }
  if (o.keepalive_time < absl::Seconds(10)) {
    return absl::InvalidArgumentError(
        "keepalive_time must be at least 10 s: fremend closes connections that ping more often");
  }
  if (o.keepalive_timeout <= absl::ZeroDuration()) {
    return absl::InvalidArgumentError("keepalive_timeout must be positive");
  }
  if (o.connect_timeout < absl::Milliseconds(100)) {
    return absl::InvalidArgumentError("connect_timeout must be at least 100 ms");
  }
  if (o.retry.multiplier < 1) return absl::InvalidArgumentError("retry.multiplier must be at least 1");
  if (o.retry.jitter < 0 || o.retry.jitter >= 1) return absl::InvalidArgumentError("retry.jitter must be in [0, 1)");
  if (o.retry.initial_backoff <= absl::ZeroDuration() || o.retry.max_backoff < o.retry.initial_backoff) {
    return absl::InvalidArgumentError("retry: need 0 < initial_backoff ≤ max_backoff");
  }
  return absl::OkStatus();
}

std::shared_ptr<grpc::ChannelCredentials> CredentialsOf(const ConnectionOptions& o) {
  if (!o.tls && o.tls_root_certs_pem.empty()) return grpc::InsecureChannelCredentials();
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = o.tls_root_certs_pem;
  ssl.pem_private_key = o.tls_client_key_pem;
  ssl.pem_cert_chain = o.tls_client_cert_pem;
  return grpc::SslCredentials(ssl);
}

grpc::ChannelArguments ChannelArgumentsOf(const ConnectionOptions& o) {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, Milliseconds(o.keepalive_time));
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, Milliseconds(o.keepalive_timeout));
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  // Keep pinging an idle connection (no data frames): a robot parked between missions still notices
  // a dead link before its next scan.
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  // gRPC reads "min reconnect backoff" as the shortest time a connection attempt is given (its
  // deadline is the later of this and the next backoff), not as a pause between attempts.
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, Milliseconds(o.connect_timeout));
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, Milliseconds(o.max_reconnect_backoff));
  args.SetMaxReceiveMessageSize(o.max_receive_message_bytes);
  if (!o.tls_server_name_override.empty()) args.SetSslTargetNameOverride(o.tls_server_name_override);
  return args;
}

}  // namespace

uint64_t RandomSeed() {
  std::random_device device;
  return (static_cast<uint64_t>(device()) << 32) ^ device();
}

absl::StatusOr<std::shared_ptr<Connection>> Connection::Open(ConnectionOptions options) {
  if (absl::Status valid = Validate(options); !valid.ok()) return valid;
  auto channel = grpc::CreateCustomChannel(options.address, CredentialsOf(options), ChannelArgumentsOf(options));
  if (channel == nullptr)
    return absl::InvalidArgumentError(absl::StrCat("address \"", options.address, "\" is not usable"));
  return std::shared_ptr<Connection>(new Connection(std::move(options), std::move(channel)));
}

Connection::Connection(ConnectionOptions options, std::shared_ptr<grpc::Channel> channel)
    : options_(std::move(options)),
      channel_(std::move(channel)),
      maps_(v1::MapService::NewStub(channel_)),
      ingest_(v1::IngestService::NewStub(channel_)),
      query_(v1::QueryService::NewStub(channel_)),
      admin_(v1::AdminService::NewStub(channel_)) {}

std::unique_ptr<grpc::ClientContext> Connection::NewContext(absl::Time deadline, absl::string_view map) const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (deadline != absl::InfiniteFuture()) context->set_deadline(absl::ToChronoTime(deadline));
  if (!options_.token.empty()) context->AddMetadata("authorization", absl::StrCat("Bearer ", options_.token));
  if (!map.empty()) context->AddMetadata("x-fremen-map", std::string(map));
  return context;
}

absl::Time Connection::DeadlineOf(const CallOptions& call) const {
  return absl::Now() + call.timeout.value_or(options_.default_timeout);
}

absl::Status Connection::CallOnce(const CallOptions& call, absl::string_view map, const Attempt& attempt) const {
  auto context = NewContext(DeadlineOf(call), map);
  return FromGrpcStatus(attempt(*context), options_.address);
}

absl::Status Connection::CallIdempotent(const CallOptions& call, absl::string_view map, const Attempt& attempt) const {
  const absl::Time deadline = DeadlineOf(call);
  Backoff backoff(options_.retry, RandomSeed());
  for (;;) {
    auto context = NewContext(deadline, map);
    absl::Status status = FromGrpcStatus(attempt(*context), options_.address);
    if (!IsRetryable(status.code()) || !backoff.MayRetry()) return status;
    const absl::Duration delay = backoff.Next();
    if (absl::Now() + delay >= deadline) return status;
    if (options_.retry.on_retry) options_.retry.on_retry(status, delay);
    PauseBeforeRetry(status, delay);
  }
}

void Connection::PauseBeforeRetry(const absl::Status& failed, absl::Duration delay) const {
  const absl::Time until = absl::Now() + delay;
  // A synchronous channel's reconnection advances only while some call polls it, and after a
  // failed connection attempt the channel fails every call at once until it is connected again.
  // So a plain sleep would leave the connection as broken as it was, and every retry would fail
  // the same way: waiting for the channel to connect is what drives the new attempt. (gRPC 1.51
  // even reports a connection still being made as failed, with a stale errno, "No such file or
  // directory", when another of the process's threads held a lock it needed; fremenctl's fleet
  // commands, a thread per daemon, met it about once in 150 runs.)
  if (failed.code() == absl::StatusCode::kUnavailable) channel_->WaitForConnected(absl::ToChronoTime(until));
  // The whole pause still, when connected early: a daemon that answered UNAVAILABLE itself (one
  // shutting down, a map moving) is not retried sooner.
  absl::SleepFor(until - absl::Now());
}

}  // namespace fremen::client
