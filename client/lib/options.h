// Options of the fremen C++ client: how to reach fremend (ConnectionOptions), how to retry
// (RetryPolicy) and per-call settings (CallOptions). Plain structs; every field says its meaning,
// its trade-off and its default.
// Thread-safety: plain values.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/time/time.h"

namespace fremen::client {

// Exponential backoff between attempts, used both for idempotent calls answered UNAVAILABLE and for
// re-opening an ingest stream after the daemon went away.
struct RetryPolicy {
  // Delay before the first retry. Default: 100 ms.
  absl::Duration initial_backoff = absl::Milliseconds(100);
  // Delays grow by `multiplier` per attempt up to this. Default: 5 s (a robot back in Wi-Fi range
  // reconnects within seconds, without hammering a restarting daemon).
  absl::Duration max_backoff = absl::Seconds(5);
  // REQUIRES: ≥ 1. Default: 2.
  double multiplier = 2.0;
  // Each delay is scaled by a random factor in [1 − jitter, 1 + jitter], so that many robots that
  // lost the daemon together do not come back in lockstep. REQUIRES: in [0, 1). Default: 0.2.
  double jitter = 0.2;
  // Attempts of one call in all (the first included); 0 = as many as fit before the call's
  // deadline. Default: 0.
  int max_attempts = 0;
  // Called before each retry of an idempotent call, with the failed attempt's status and the delay
  // about to be slept (for logging or counting; it must not block). Default: none.
  std::function<void(const absl::Status&, absl::Duration)> on_retry;
};

struct ConnectionOptions {
  // host:port of fremend (any gRPC target: "dns:///robots.example:50051", "unix:/run/fremen.sock").
  // Default: 127.0.0.1:50051.
  std::string address = "127.0.0.1:50051";
  // Use TLS. Implied by a non-empty tls_root_certs_pem. Default: false (fremend's default listens
  // on loopback without TLS).
  bool tls = false;
  // PEM root certificates that sign the daemon's certificate; empty = the system's roots.
  std::string tls_root_certs_pem;
  // Client certificate and key (PEM) for a daemon that verifies clients (tls_client_ca_file);
  // both or neither.
  std::string tls_client_cert_pem;
  std::string tls_client_key_pem;
  // Expect this name in the daemon's certificate instead of the address's host (tests, or an
  // address by IP). Empty = the host.
  std::string tls_server_name_override;
  // Bearer token sent as "authorization: Bearer <token>" on every call; empty = none (a daemon
  // without configured tokens).
  std::string token;
  // Deadline of a call that names none in its CallOptions, covering all its retries. Long-running
  // calls (BackupMap) may need more. Default: 30 s.
  absl::Duration default_timeout = absl::Seconds(30);
  // HTTP/2 keepalive, for robots on Wi-Fi: ping every keepalive_time, even without calls, and
  // declare the connection dead when no answer comes within keepalive_timeout, so that a link that
  // silently dropped is noticed in ~30 s rather than at TCP's pace. fremend accepts pings down to
  // 10 s apart (config keepalive_min_client_interval); faster ones get the connection closed.
  // Defaults: 20 s and 10 s.
  absl::Duration keepalive_time = absl::Seconds(20);
  absl::Duration keepalive_timeout = absl::Seconds(10);
  // The channel's own reconnect backoff ceiling (gRPC's default is 120 s, too slow for a robot
  // that comes back into range). Default: 5 s.
  absl::Duration max_reconnect_backoff = absl::Seconds(5);
  // How long one connection attempt may take, TCP connect and HTTP/2 handshake (the server's
  // SETTINGS) together, before it is abandoned and retried after the backoff. A loaded daemon or a
  // slow Wi-Fi link can take hundreds of milliseconds; an attempt cut shorter never connects.
  // Default: 20 s (gRPC's own).
  absl::Duration connect_timeout = absl::Seconds(20);
  // Largest message received (region chunks stay under 1 MiB; predictions of many states × times
  // can be larger). Default: 64 MiB.
  int max_receive_message_bytes = 64 << 20;
  // Retries of idempotent calls on UNAVAILABLE.
  RetryPolicy retry;
};

// Per call.
struct CallOptions {
  // The call's deadline, retries included; unset = ConnectionOptions::default_timeout.
  std::optional<absl::Duration> timeout;
};

}  // namespace fremen::client
