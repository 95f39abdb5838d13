// fremend's life: Start() brings the daemon up step by step, each step checked and logged, and
// Stop() takes it down in reverse.
//
// Start: data directory (created, locked against a second daemon) → credentials → gRPC server listening, health NOT_SERVING
// → HTTP port listening (server/http/: /readyz says 503 until serving; server/gateway/: the JSON API, into the gRPC
// server's in-process channel) → store opened
// (recovery: every map's checkpoint, then its log) → health SERVING → update schedule. Calls that arrive during
// recovery get UNAVAILABLE (server/rpc/store_handle.h).
// Stop: update schedule stopped → health NOT_SERVING, /readyz 503, and new calls refused (UNAVAILABLE) → the calls in
// flight get up to shutdown_grace to finish → gRPC shuts down at once, cancelling what is left → the HTTP port closes → the blocking pool
// finishes its work → update jobs end (a publication under way finishes) → the store finishes queued writes and checkpoints.
//
// The services served are added in one place, Daemon::AddServices.
// Thread-safety: Start and Stop from one thread (main); the services run on gRPC's threads.
#pragma once

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "server/rpc/auth.h"
#include "server/rpc/blocking_pool.h"
#include "server/daemon/config.h"
#include "server/daemon/data_dir_lock.h"
#include "server/http/http_server.h"
#include "server/rpc/call_tracker.h"
#include "server/jobs/operations.h"
#include "server/metrics/metrics.h"
#include "server/rpc/store_handle.h"
#include "server/rpc/unary_call.h"
#include "server/jobs/scrubber.h"
#include "server/jobs/update_scheduler.h"
#include "storage/store.h"

namespace fremen::server {

class Daemon {
 public:
  explicit Daemon(ServerConfig config);
  ~Daemon();

  // The error names the step that failed. Call Stop() afterwards either way.
  absl::Status Start();
  // Idempotent. The error is the store's, when closing it failed (data may not be flushed).
  absl::Status Stop();

  // HOST:PORT the server listens on (the port chosen, when the config said 0).
  const std::string& address() const { return address_; }
  // HOST:PORT of the HTTP port; "" when http_listen is empty.
  std::string http_address() const { return http_ == nullptr ? "" : http_->address(); }

 private:
  absl::Status PrepareDirectories();
  std::shared_ptr<grpc::ServerCredentials> Credentials() const;
  void AddServices(grpc::ServerBuilder& builder);
  void SetChannelArguments(grpc::ServerBuilder& builder) const;
  absl::Status StartServer();
  // The HTTP port and its routes, when http_listen is set.
  absl::Status StartHttp();
  void AddHttpRoutes(httplib::Server& routes);
  absl::Status OpenStore();
  // The update jobs' registry and schedule, and the background scrub, for the admin service.
  absl::Status PrepareUpdates();
  void SetServing(bool serving);

  ServerConfig config_;
  Metrics metrics_;  // observed by the services, the store and the jobs: outlives them all
  CallTracker calls_;
  Authenticator auth_;
  BlockingPool blocking_;
  StoreHandle store_handle_;
  ServiceDeps deps_;
  std::unique_ptr<DataDirLock> data_dir_lock_;  // released after the store is closed
  std::unique_ptr<storage::Store> store_;
  // Update jobs read the store: declared after it, so destroyed before it (Stop stops them first).
  std::unique_ptr<OperationRegistry> operations_;
  std::unique_ptr<UpdateScheduler> scheduler_;  // starts operations: destroyed before them
  std::unique_ptr<Scrubber> scrubber_;           // reads the store: stopped before it closes
  std::vector<std::unique_ptr<grpc::Service>> services_;
  std::vector<std::string> service_names_;  // for health: each service, and "" for the whole server
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
  // The JSON API's in-process channel into server_ (server/gateway/json_api.h).
  std::shared_ptr<grpc::Channel> gateway_channel_;
  std::unique_ptr<HttpServer> http_;  // its handlers call into server_: stopped after it drains
  std::atomic<bool> serving_ = false;  // what health says, for /readyz
  std::atomic<bool> stopped_ = false;  // read by /readyz
};

}  // namespace fremen::server
