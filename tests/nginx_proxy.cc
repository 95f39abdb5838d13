#include "tests/nginx_proxy.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <thread>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "tests/fremend_fixture.h"
#include "tests/process_runner.h"

namespace fremen::testing {

namespace {

constexpr auto kStartTimeout = std::chrono::seconds(30);

// Whether something accepts TCP connections at "127.0.0.1:PORT".
bool Accepts(const std::string& address) {
  int port = 0;
  if (!absl::SimpleAtoi(address.substr(address.rfind(':') + 1), &port)) return false;
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  to.sin_port = htons(static_cast<uint16_t>(port));
  const bool connected = fd >= 0 && connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) == 0;
  if (fd >= 0) close(fd);
  return connected;
}

std::vector<std::string> NginxArgs(const std::string& dir, const std::string& config) {
  return {"-p", dir, "-c", config, "-e", absl::StrCat(dir, "/error.log")};
}

}  // namespace

std::string NginxBinary() { return access("/usr/sbin/nginx", X_OK) == 0 ? "/usr/sbin/nginx" : ""; }

namespace {

// render.py's arguments (after the interpreter) for `daemons`, writing `config`.
std::vector<std::string> RenderArgs(const std::string& dir, const std::vector<ProxiedDaemon>& daemons,
                                    const std::string& grpc_listen, const std::string& http_listen,
                                    const std::string& config) {
  std::vector<std::string> args = {absl::StrCat(FREMEN_SOURCE_DIR, "/deploy/nginx/render.py"),
                                   "--grpc-listen",
                                   grpc_listen,
                                   "--http-listen",
                                   http_listen,
                                   "--runtime-dir",
                                   dir,
                                   "--out",
                                   config};
  for (const ProxiedDaemon& d : daemons) args.insert(args.end(), {"--daemon", absl::StrCat(d.grpc, "=", d.http)});
  return args;
}

}  // namespace

absl::StatusOr<std::string> RenderNginxConfig(const std::string& dir, const std::vector<ProxiedDaemon>& daemons,
                                              const std::string& grpc_listen, const std::string& http_listen) {
  const std::string config = absl::StrCat(dir, "/nginx.conf");
  const std::vector<std::string> args = RenderArgs(dir, daemons, grpc_listen, http_listen, config);
  const RunResult rendered = RunProgram("/usr/bin/python3", args);
  if (rendered.exit_code != 0) {
    return absl::InternalError(absl::StrCat("render.py: ", Describe(rendered), ": ", rendered.err));
  }
  std::vector<std::string> test = NginxArgs(dir, config);
  test.push_back("-t");
  const RunResult checked = RunProgram(NginxBinary(), test);
  if (checked.exit_code != 0) {
    return absl::InvalidArgumentError(absl::StrCat("nginx -t: ", Describe(checked), ": ", checked.err));
  }
  return config;
}

absl::StatusOr<std::unique_ptr<NginxProxy>> NginxProxy::Start(const std::string& dir,
                                                              const std::vector<ProxiedDaemon>& daemons,
                                                              bool master_process) {
  const std::string grpc_address = FreeLoopbackAddress();
  const std::string http_address = FreeLoopbackAddress();
  auto config = RenderNginxConfig(dir, daemons, grpc_address, http_address);
  if (!config.ok()) return config.status();
  std::vector<std::string> args = NginxArgs(dir, *config);
  // In the foreground: killed with the test (PDEATHSIG). One process, unless the test reloads it.
  args.insert(args.end(), {"-g", master_process ? "daemon off;" : "daemon off; master_process off;"});
  const std::string out_path = absl::StrCat(dir, "/nginx.out");
  const pid_t pid = SpawnBackground(NginxBinary(), args, out_path);
  if (pid < 0) return absl::InternalError("fork failed");
  std::unique_ptr<NginxProxy> proxy(new NginxProxy(pid, dir, grpc_address, http_address));
  const auto deadline = std::chrono::steady_clock::now() + kStartTimeout;
  while (!(Accepts(grpc_address) && Accepts(http_address))) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      proxy->pid_ = -1;
      return absl::InternalError(absl::StrCat("nginx exited at start: ", ReadTextFile(out_path), proxy->ErrorLog()));
    }
    if (std::chrono::steady_clock::now() > deadline) {
      return absl::DeadlineExceededError(absl::StrCat("nginx does not accept connections: ", proxy->ErrorLog()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return proxy;
}

NginxProxy::~NginxProxy() {
  if (pid_ <= 0) return;
  kill(pid_, SIGTERM);
  int status = 0;
  waitpid(pid_, &status, 0);
}

std::string NginxProxy::AccessLog(size_t lines) const {
  const auto deadline = std::chrono::steady_clock::now() + kStartTimeout;
  for (;;) {
    std::string log = ReadTextFile(absl::StrCat(dir_, "/access.log"));
    if (static_cast<size_t>(std::count(log.begin(), log.end(), '\n')) >= lines ||
        std::chrono::steady_clock::now() > deadline) {
      return log;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}
std::string NginxProxy::ReloadCommand(const std::vector<ProxiedDaemon>& daemons) const {
  const std::string config = absl::StrCat(dir_, "/nginx.conf");
  std::vector<std::string> render = RenderArgs(dir_, daemons, grpc_address_, http_address_, config);
  render.insert(render.begin(), "/usr/bin/python3");
  std::vector<std::string> reload = NginxArgs(dir_, config);
  reload.insert(reload.begin(), NginxBinary());
  reload.insert(reload.end(), {"-s", "reload"});
  return absl::StrCat(absl::StrJoin(render, " "), " && ", absl::StrJoin(reload, " "));
}

std::string NginxProxy::ErrorLog() const { return ReadTextFile(absl::StrCat(dir_, "/error.log")); }

}  // namespace fremen::testing
