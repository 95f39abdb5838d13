// fremend's HTTP port (setting http_listen): one listener, plain or TLS with the daemon's own
// certificate (and client CA: mutual TLS), on which the routes of server/http/ are registered
// before Start. Served by cpp-httplib (Debian's libcpp-httplib) on its own thread pool, apart from
// gRPC's threads.
//
// Start binds (port 0 = any free port; address() then says which) and serves on a thread of its
// own; Stop stops accepting, ends the connections and joins. Routes must be registered before
// Start; a handler runs on one of httplib's pool threads.
// Thread-safety: Start and Stop from one thread; handlers on httplib's threads.
#pragma once

#include <httplib.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "absl/status/status.h"

namespace fremen::server {

class HttpServer {
 public:
  struct Options {
    std::string listen;  // HOST:PORT; IPv6 hosts in brackets
    // TLS: both or neither (as the daemon's gRPC port); with a client CA, clients must present a
    // certificate it signed.
    std::string tls_cert_file, tls_key_file, tls_client_ca_file;
  };

  explicit HttpServer(Options options);
  ~HttpServer();  // Stop()

  // Where routes are registered, before Start.
  httplib::Server& routes() { return *server_; }

  // The error names http_listen (the address in use, a bad certificate).
  absl::Status Start();
  // Idempotent.
  void Stop();

  // HOST:PORT listened on (the port chosen, when the setting said 0).
  const std::string& address() const { return address_; }
  bool tls() const { return !options_.tls_cert_file.empty(); }

 private:
  Options options_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  std::atomic<bool> loop_ended_ = false;
  std::string address_;
};

}  // namespace fremen::server
