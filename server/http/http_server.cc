#include "server/http/http_server.h"

#include <sys/socket.h>

#include <chrono>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"

namespace fremen::server {

namespace {

// Slow clients get this long per read and write; a stuck one frees its pool thread after it.
constexpr time_t kIoTimeoutSeconds = 30;

std::unique_ptr<httplib::Server> NewServer(const HttpServer::Options& options) {
  if (options.tls_cert_file.empty()) return std::make_unique<httplib::Server>();
  return std::make_unique<httplib::SSLServer>(
      options.tls_cert_file.c_str(), options.tls_key_file.c_str(),
      options.tls_client_ca_file.empty() ? nullptr : options.tls_client_ca_file.c_str());
}

}  // namespace

HttpServer::HttpServer(Options options) : options_(std::move(options)), server_(NewServer(options_)) {
  // httplib's default also sets SO_REUSEPORT, with which a second daemon on the same port would
  // start and share the connections instead of failing; SO_REUSEADDR alone lets a restart rebind
  // while old connections linger in TIME_WAIT.
  server_->set_socket_options([](socket_t sock) {
    const int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  server_->set_read_timeout(kIoTimeoutSeconds);
  server_->set_write_timeout(kIoTimeoutSeconds);
}

HttpServer::~HttpServer() { Stop(); }

absl::Status HttpServer::Start() {
  if (!server_->is_valid()) {
    return absl::InvalidArgumentError("http_listen: cannot serve TLS with tls_cert_file and tls_key_file");
  }
  const size_t colon = options_.listen.rfind(':');
  std::string host = options_.listen.substr(0, colon);
  int port = 0;
  if (colon == std::string::npos || !absl::SimpleAtoi(absl::string_view(options_.listen).substr(colon + 1), &port)) {
    return absl::InvalidArgumentError(absl::StrCat("http_listen: \"", options_.listen, "\" is not HOST:PORT"));
  }
  const std::string bind_host = absl::StartsWith(host, "[") ? host.substr(1, host.size() - 2) : host;
  if (absl::StrContains(bind_host, ':')) server_->set_address_family(AF_INET6);
  const int bound = port == 0 ? server_->bind_to_any_port(bind_host) : (server_->bind_to_port(bind_host, port) ? port : -1);
  if (bound <= 0) {
    return absl::UnavailableError(
        absl::StrCat("http_listen: cannot listen on ", options_.listen, " (address in use or not local)"));
  }
  address_ = absl::StrCat(host, ":", bound);
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    loop_ended_ = true;
  });
  // httplib's stop() does nothing until its loop runs: wait for it, so that a Stop right after
  // Start is not lost.
  while (!server_->is_running() && !loop_ended_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return absl::OkStatus();
}

void HttpServer::Stop() {
  if (!thread_.joinable()) return;
  server_->stop();
  thread_.join();
}

}  // namespace fremen::server
