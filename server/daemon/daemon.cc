#include "server/daemon/daemon.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <system_error>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "server/dashboard/dashboard_routes.h"
#include "server/gateway/json_api.h"
#include "server/http/health_routes.h"
#include "server/metrics/metrics_route.h"
#include "server/services/admin_service.h"
#include "server/services/ingest_service.h"
#include "server/rpc/logging.h"
#include "server/jobs/map_list.h"
#include "server/services/map_service.h"
#include "server/services/query_service.h"
#include "server/jobs/update_job.h"
#include "storage/map_page.h"

namespace fremen::server {

namespace {

namespace fs = std::filesystem;

// Queued blocking calls beyond which new ones are refused (RESOURCE_EXHAUSTED): create/delete/backup
// are rare; a queue this deep means the disk cannot keep up.
constexpr size_t kMaxQueuedBlockingCalls = 256;


std::string HostOf(const std::string& listen) { return listen.substr(0, listen.rfind(':')); }

bool IsLoopback(const std::string& host) {
  return host == "127.0.0.1" || host == "localhost" || host == "[::1]" || host.rfind("127.", 0) == 0;
}

absl::Status MakeDirectory(const std::string& key, const fs::path& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) return absl::FailedPreconditionError(absl::StrCat(key, ": cannot create ", dir.string(), ": ", error.message()));
  if (access(dir.c_str(), W_OK | X_OK) != 0) {
    return absl::FailedPreconditionError(absl::StrCat(key, ": ", dir.string(), " is not writable by this user"));
  }
  return absl::OkStatus();
}

absl::StatusOr<uint64_t> CountMaps(const storage::Store& store) {
  uint64_t count = 0;
  std::string token;
  do {
    auto page = store.ListMaps(storage::kMaxPageSize, token);
    if (!page.ok()) return page.status();
    count += page->maps.size();
    token = page->next_page_token;
  } while (!token.empty());
  return count;
}

}  // namespace

Daemon::Daemon(ServerConfig config)
    : config_(std::move(config)),
      auth_(config_.tokens),
      blocking_("blocking", config_.blocking_threads, kMaxQueuedBlockingCalls),
      deps_{&calls_, &auth_, &blocking_, &store_handle_, metrics_.calls()} {}

Daemon::~Daemon() { (void)Stop(); }

absl::Status Daemon::Start() {
  DaemonLog()->info("fremend {} starting", FREMEN_VERSION);
  if (absl::Status s = PrepareDirectories(); !s.ok()) return s;
  if (absl::Status s = PrepareUpdates(); !s.ok()) return s;
  if (absl::Status s = StartServer(); !s.ok()) return s;
  if (absl::Status s = StartHttp(); !s.ok()) return s;
  if (absl::Status s = OpenStore(); !s.ok()) return s;
  SetServing(true);
  scheduler_->Start();
  scrubber_->Start();
  auto maps = CountMaps(*store_);
  const size_t failed = store_->FailedMaps().size();
  DaemonLog()->info("fremend listening on {}, data in {} ({} maps{}){}", address_, config_.data_dir, maps.ok() ? *maps : 0,
              failed == 0 ? "" : absl::StrCat(", ", failed, " failed"), auth_.enabled() ? ", tokens required" : "");
  return absl::OkStatus();
}

absl::Status Daemon::PrepareDirectories() {
  config_.data_dir = fs::absolute(config_.data_dir).lexically_normal().string();
  if (config_.backup_dir.empty()) config_.backup_dir = (fs::path(config_.data_dir) / "backups").string();
  config_.backup_dir = fs::absolute(config_.backup_dir).lexically_normal().string();
  if (absl::Status s = MakeDirectory("data_dir", config_.data_dir); !s.ok()) return s;
  auto lock = DataDirLock::Acquire(config_.data_dir);
  if (!lock.ok()) return lock.status();
  data_dir_lock_ = *std::move(lock);
  return absl::OkStatus();  // backup_dir is created on the first backup: it may be on a disk mounted later
}

std::shared_ptr<grpc::ServerCredentials> Daemon::Credentials() const {
  const bool loopback = IsLoopback(HostOf(config_.listen));
  if (config_.tls_cert_pem.empty()) {
    if (auth_.enabled() && !loopback) {
      DaemonLog()->warn("bearer tokens are configured without TLS on {}: they cross the network in clear text",
                  config_.listen);
    }
    return grpc::InsecureServerCredentials();
  }
  grpc::SslServerCredentialsOptions options(config_.tls_client_ca_pem.empty()
                                                ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                                : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_root_certs = config_.tls_client_ca_pem;
  options.pem_key_cert_pairs.push_back({config_.tls_key_pem, config_.tls_cert_pem});
  return grpc::SslServerCredentials(options);
}

// Every service the daemon serves. A service is added only once all its methods work.
void Daemon::AddServices(grpc::ServerBuilder& builder) {
  services_.push_back(std::make_unique<MapServiceImpl>(deps_));
  service_names_.push_back(v1::MapService::service_full_name());
  services_.push_back(std::make_unique<IngestServiceImpl>(deps_));
  service_names_.push_back(v1::IngestService::service_full_name());
  services_.push_back(std::make_unique<QueryServiceImpl>(deps_));
  service_names_.push_back(v1::QueryService::service_full_name());
  services_.push_back(std::make_unique<AdminServiceImpl>(
      deps_, AdminDeps{operations_.get(), scheduler_.get(), scrubber_.get(), &config_, &RealClock::Get()}));
  service_names_.push_back(v1::AdminService::service_full_name());
  for (const auto& service : services_) builder.RegisterService(service.get());
  service_names_.push_back("");  // the whole server
}

void Daemon::SetChannelArguments(grpc::ServerBuilder& builder) const {
  const int max_message_bytes = static_cast<int>(config_.max_message_mb) << 20;
  builder.SetMaxReceiveMessageSize(max_message_bytes);
  builder.SetMaxSendMessageSize(max_message_bytes);
  // gRPC sets SO_REUSEPORT by default: a second daemon on the same port would start and share the
  // connections with the first instead of failing.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  const auto ms = [](absl::Duration d) { return static_cast<int>(absl::ToInt64Milliseconds(d)); };
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, ms(config_.keepalive_time));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, ms(config_.keepalive_timeout));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, config_.keepalive_permit_without_calls ? 1 : 0);
  // Keep pinging an idle robot however long it stays idle (the default stops after two pings).
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  // Robots' own keepalive pings, down to this interval, are welcome rather than a protocol abuse.
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS,
                             ms(config_.keepalive_min_client_interval));
}

absl::Status Daemon::StartServer() {
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(config_.listen, Credentials(), &port);
  SetChannelArguments(builder);
  AddServices(builder);
  server_ = builder.BuildAndStart();
  if (server_ == nullptr || port == 0) {
    server_.reset();
    return absl::UnavailableError(absl::StrCat(
        "listen: cannot listen on ", config_.listen, " (address in use or not local",
        config_.tls_cert_pem.empty() ? "" : ", or the TLS certificate and key do not match", ")"));
  }
  address_ = absl::StrCat(HostOf(config_.listen), ":", port);
  SetServing(false);  // until the maps are recovered
  DaemonLog()->info("serving gRPC on {}{} (NOT_SERVING until the maps are recovered)", address_,
       config_.tls_cert_pem.empty() ? "" : " with TLS");
  return absl::OkStatus();
}

absl::Status Daemon::StartHttp() {
  if (config_.http_listen.empty()) {
    DaemonLog()->info("no HTTP port (http_listen is empty)");
    return absl::OkStatus();
  }
  // The JSON API's channel into the services: the gRPC server is built (StartServer came first),
  // so its in-process channel exists before any HTTP request does. Its message limits are the
  // server's own, for the same answers a remote client may get.
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(static_cast<int>(config_.max_message_mb) << 20);
  args.SetMaxSendMessageSize(static_cast<int>(config_.max_message_mb) << 20);
  gateway_channel_ = server_->InProcessChannel(args);
  http_ = std::make_unique<HttpServer>(HttpServer::Options{config_.http_listen, config_.tls_cert_file,
                                                           config_.tls_key_file, config_.tls_client_ca_file});
  AddHttpRoutes(http_->routes());
  if (absl::Status s = http_->Start(); !s.ok()) return s;
  DaemonLog()->info("serving HTTP on {}{} (the dashboard at /, /v1/... JSON API, /metrics, /healthz, /readyz)",
                    http_->address(), http_->tls() ? " with TLS" : "");
  return absl::OkStatus();
}

// Every route of the HTTP port.
void Daemon::AddHttpRoutes(httplib::Server& routes) {
  AddHealthRoutes(routes, [this]() -> std::string {
    if (serving_) return "";
    return stopped_ ? "shutting down" : "recovering the maps";
  });
  AddMetricsRoute(routes, &metrics_, &auth_);
  AddDashboardRoutes(routes);
  // Set before the HTTP port starts and reset after it stops: no handler sees it change.
  AddJsonApi(routes, [this] { return gateway_channel_; });
}

absl::Status Daemon::PrepareUpdates() {
  OperationRegistry::Options jobs;
  jobs.on_finished = [metrics = metrics_.jobs()](const OperationView& operation) { metrics->Finished(operation); };
  operations_ = std::make_unique<OperationRegistry>(StoreUpdateJob(&store_handle_), RealClock::Get(), jobs);
  metrics_.Watch(&store_handle_, operations_.get());
  auto scheduler = NewStoreUpdateScheduler(config_, RealClock::Get(), &store_handle_, operations_.get());
  if (!scheduler.ok()) return scheduler.status();
  scheduler_ = *std::move(scheduler);
  Scrubber::Options scrub;
  scrub.interval = config_.scrub_interval;
  scrub.map_timeout = config_.scrub_map_timeout;
  scrubber_ = std::make_unique<Scrubber>(
      scrub, RealClock::Get(), [this] { return ListAllMapNames(store_handle_); },
      [this](const std::string& name, absl::Time deadline) -> absl::StatusOr<storage::VerifyReport> {
        auto store = store_handle_.Get();
        if (!store.ok()) return store.status();
        auto map = (*store)->Map(name);  // a failed map is not open, and not scrubbed
        if (!map.ok()) return map.status();
        return (*map)->Verify(deadline);
      });
  return absl::OkStatus();
}

absl::Status Daemon::OpenStore() {
  storage::StoreOptions options;
  options.default_shards = config_.shards;
  options.checkpoint_log_bytes = config_.checkpoint_log_mb << 20;
  options.publication_waits_for_a_batch = config_.test_publication_waits_for_a_batch;
  options.observer = metrics_.store();
  const auto store_log = NamedLogger(kStoreLogger);
  // What recovery repairs on its own (a torn log tail cut) is logged at warning.
  options.log_warning = [store_log](const std::string& line) { store_log->warn("{}", line); };
  store_log->info("opening {} (recovering every map)", config_.data_dir);
  const absl::Time start = absl::Now();
  auto store = storage::Store::Open(config_.data_dir, options);
  if (!store.ok()) {
    return absl::Status(store.status().code(), absl::StrCat("store: cannot open ", config_.data_dir, ": ",
                                                            store.status().message()));
  }
  store_ = *std::move(store);
  store_handle_.Publish(store_.get());
  store_log->info("opened in {}", absl::FormatDuration(absl::Now() - start));
  // A map that did not open fails alone: the daemon serves the others (health stays SERVING) and
  // says why here and in GetServerStatus' failed_maps.
  for (const storage::FailedMap& failed : store_->FailedMaps()) {
    store_log->error("map {} is failed and not served: {}", failed.name, failed.status.ToString());
  }
  for (const std::string& dir : store_->UnknownDirectories()) {
    store_log->warn("{} is not a map of the catalog: left as it is for an operator (GetServerStatus lists it)", dir);
  }
  return absl::OkStatus();
}

void Daemon::SetServing(bool serving) {
  serving_ = serving;
  grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService();
  for (const std::string& name : service_names_) health->SetServingStatus(name, serving);
}

absl::Status Daemon::Stop() {
  if (stopped_) return absl::OkStatus();
  stopped_ = true;
  if (scheduler_ != nullptr) scheduler_->Stop();  // no new scheduled updates while stopping
  if (scrubber_ != nullptr) scrubber_->Stop();    // after the map it is verifying
  if (server_ != nullptr) {
    DaemonLog()->info("stopping: NOT_SERVING, no new calls, up to {} for the calls in flight",
                absl::FormatDuration(config_.shutdown_grace));
    serving_ = false;
    server_->GetHealthCheckService()->Shutdown();  // every service NOT_SERVING, for good
    if (const int64_t left = calls_.Drain(config_.shutdown_grace); left > 0) {
      DaemonLog()->warn("{} calls still in flight after {}: cancelling them", left,
                  absl::FormatDuration(config_.shutdown_grace));
    }
    server_->Shutdown(std::chrono::system_clock::now());
  }
  if (http_ != nullptr) http_->Stop();
  gateway_channel_.reset();  // before the server it leads into
  blocking_.Stop();
  // A publication under way finishes (it is short and atomic in the log); queued updates are cancelled.
  if (operations_ != nullptr) operations_->Stop();
  absl::Status closed;
  if (store_ != nullptr) {
    closed = store_->Close();
    if (closed.ok()) {
      NamedLogger(kStoreLogger)->info("closed: every acknowledged write is checkpointed");
    } else {
      NamedLogger(kStoreLogger)->error("closing failed: {}", std::string(closed.message()));
    }
  }
  server_.reset();
  DaemonLog()->info("stopped");
  return closed;
}

}  // namespace fremen::server
