// End-to-end test support for a fleet (docs/fleet.md): a real nginx in front of real fremend
// daemons, configured by the deployment's own renderer (deploy/nginx/render.py) — the
// configuration under test is the one that ships.
//
// NginxProxy::Start renders the configuration into a directory the test owns (pid file, logs,
// temporary files there too), runs `nginx -t` on it, then nginx in the foreground as one process
// (master_process off: it dies with the test process, like the daemons of fremend_fixture.h), and
// returns once its gRPC port accepts connections. A test that reconfigures the proxy (a rebalance)
// starts it with a master process and one worker instead, as nginx runs in production: a reload
// then starts a new worker with the new configuration and the old one closes its connections
// gracefully (HTTP/2 GOAWAY), so that clients' next calls take the new routes; in one process a
// reload would leave open connections on the old configuration. The test is skipped when nginx is not installed
// (scripts/install-deps.sh installs nginx-light).
// Thread-compatible: one test thread drives a proxy.
#pragma once

#include <sys/types.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace fremen::testing {

// Where nginx is (Debian's nginx-light); "" when it is not installed.
std::string NginxBinary();

// A daemon as the proxy sees it: its gRPC and HTTP addresses.
struct ProxiedDaemon {
  std::string grpc, http;
};

// `render.py` and `nginx -t` for `daemons`, listening on `grpc_listen` and `http_listen`, with the
// runtime files in `dir`: the configuration's path, or the renderer's or nginx's complaint.
absl::StatusOr<std::string> RenderNginxConfig(const std::string& dir, const std::vector<ProxiedDaemon>& daemons,
                                              const std::string& grpc_listen, const std::string& http_listen);

class NginxProxy {
 public:
  // `dir` must exist; the proxy listens on free loopback ports.
  static absl::StatusOr<std::unique_ptr<NginxProxy>> Start(const std::string& dir,
                                                           const std::vector<ProxiedDaemon>& daemons,
                                                           bool master_process = false);
  // Stops nginx (SIGTERM) and waits.
  ~NginxProxy();

  const std::string& grpc_address() const { return grpc_address_; }
  const std::string& http_address() const { return http_address_; }
  // nginx's access log once it has at least `lines` lines (nginx writes a request's line after its
  // answer: the client can be faster), or after 30 s as it is: one line per request, with
  // map="..." and upstream=ADDRESS.
  std::string AccessLog(size_t lines = 0) const;
  // Its error log so far.
  std::string ErrorLog() const;
  // A shell command that renders the configuration for `daemons` over this proxy's (same listen
  // addresses and directory) and reloads nginx (`nginx -s reload`): a rebalance's --proxy-command.
  std::string ReloadCommand(const std::vector<ProxiedDaemon>& daemons) const;

 private:
  NginxProxy(pid_t pid, std::string dir, std::string grpc_address, std::string http_address)
      : pid_(pid),
        dir_(std::move(dir)),
        grpc_address_(std::move(grpc_address)),
        http_address_(std::move(http_address)) {}

  pid_t pid_;
  const std::string dir_;
  const std::string grpc_address_, http_address_;
};

}  // namespace fremen::testing
