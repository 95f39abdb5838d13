// End-to-end test support: the real fremend binary (FREMEND_BINARY, set by CMake) run as a child
// process on a free loopback port, with a data directory the test owns, and gRPC channels to it.
//
// FremendProcess::Start passes --listen 127.0.0.1:0 and --http-listen 127.0.0.1:0 (the daemon logs the
// ports it was given) unless the test's args have their own (FreeLoopbackPort: a daemon restarted on the same
// address, as its clients expect),
// sends the daemon's output to a log file, and returns once the daemon has logged its address and
// the health service says SERVING. Stop() sends SIGTERM and returns the exit code; Kill() is
// kill -9. A test restarts a daemon on the same data directory to check what survives. A daemon
// dies with the test process that started it, even when the test crashes.
// Thread-compatible: one test thread drives a process.
#pragma once

#include <grpcpp/grpcpp.h>
#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "gtest/gtest.h"
#include "testing/temp_dir.h"
#include "tests/free_port.h"
#include "tests/process_runner.h"

namespace fremen::testing {

// A self-signed certificate for 127.0.0.1 and localhost, made with the openssl command line into
// `dir` (cert.pem, key.pem). nullopt when openssl cannot make one (the test then skips).
struct TestCertificate {
  std::string cert_path, key_path;
  std::string cert_pem;  // the certificate itself: the root a client trusts
};
std::optional<TestCertificate> MakeTestCertificate(const TempDir& dir);

// Runs fremend with `args` to completion (help, bad configuration, --check-config, --verify).
RunResult RunFremend(const std::vector<std::string>& args, const RunOptions& options = {});

class FremendProcess {
 public:
  // Starts fremend serving `data_dir`, with `args` added to the command line, and waits until it
  // is SERVING (talking to it with `credentials`). The error carries the daemon's log.
  static absl::StatusOr<std::unique_ptr<FremendProcess>> Start(
      const std::string& data_dir, const std::vector<std::string>& args = {},
      std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials());
  // Kills the daemon when a test left it running.
  ~FremendProcess();

  const std::string& address() const { return address_; }
  // HOST:PORT of its HTTP port ("" when it has none: --http-listen "").
  const std::string& http_address() const { return http_address_; }
  pid_t pid() const { return pid_; }
  // A new channel to the daemon, with the credentials Start was given.
  std::shared_ptr<grpc::Channel> NewChannel() const;

  // Sends `signal` (SIGTERM or SIGINT), then waits for the exit (SIGKILL after a minute). The exit
  // code; -1 when the daemon died of a signal or had to be killed.
  int Stop(int signal = SIGTERM);
  // kill -9, and waits.
  void Kill();
  // Everything the daemon has written so far.
  std::string Log() const;

 private:
  FremendProcess(pid_t pid, std::string log_path, std::shared_ptr<grpc::ChannelCredentials> credentials)
      : pid_(pid), log_path_(std::move(log_path)), credentials_(std::move(credentials)) {}
  absl::Status AwaitServing();
  // The exit code once the process has ended, -1 for a signal; nullopt while it runs.
  std::optional<int> Reap(bool block);

  pid_t pid_;
  const std::string log_path_;
  std::shared_ptr<grpc::ChannelCredentials> credentials_;
  std::string address_;
  std::string http_address_;
  bool running_ = true;
  int exit_code_ = -1;
};

// A client context with a deadline (so that a hung daemon fails the test instead of hanging it)
// and the given metadata, e.g. {{"authorization", "Bearer t"}, {"x-fremen-map", "lab"}}.
std::unique_ptr<grpc::ClientContext> CallContext(
    const std::vector<std::pair<std::string, std::string>>& metadata = {},
    std::chrono::seconds deadline = std::chrono::seconds(30));

// A test with one daemon on a fresh data directory: started before each test, and stopped after it
// with SIGTERM, expecting exit code 0.
class DaemonTest : public ::testing::Test {
 protected:
  void SetUp() override { StartDaemon(); }
  void TearDown() override;

  // (Re)starts the daemon on the test's data directory with `args` added; a fatal failure when it
  // does not come up.
  void StartDaemon(const std::vector<std::string>& args = {},
                   std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials());
  // Stops the daemon, expecting exit code 0.
  void StopDaemon();

  std::string data_dir() const { return dir_.Path("data"); }

  TempDir dir_;
  std::unique_ptr<FremendProcess> daemon_;
};

}  // namespace fremen::testing
