#include "tests/fremend_fixture.h"

#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <sstream>
#include <thread>

#include "absl/strings/str_cat.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace fremen::testing {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr auto kStartTimeout = std::chrono::seconds(60);
constexpr auto kStopTimeout = std::chrono::seconds(60);
constexpr auto kPollInterval = std::chrono::milliseconds(20);

// The exit code of a waitpid status; -1 for a signal.
int ExitCodeOf(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

}  // namespace

std::optional<TestCertificate> MakeTestCertificate(const TempDir& dir) {
  TestCertificate made{dir.Path("cert.pem"), dir.Path("key.pem"), ""};
  const std::string openssl = "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 1"
                              " -subj /CN=localhost -addext subjectAltName=IP:127.0.0.1,DNS:localhost"
                              " -keyout '" + made.key_path + "' -out '" + made.cert_path + "' >/dev/null 2>&1";
  if (std::system(openssl.c_str()) != 0) return std::nullopt;
  made.cert_pem = ReadTextFile(made.cert_path);
  return made;
}

RunResult RunFremend(const std::vector<std::string>& args, const RunOptions& options) {
  return RunProgram(FREMEND_BINARY, args, options);
}

absl::StatusOr<std::unique_ptr<FremendProcess>> FremendProcess::Start(
    const std::string& data_dir, const std::vector<std::string>& args,
    std::shared_ptr<grpc::ChannelCredentials> credentials) {
  std::vector<std::string> all_args = {"--data-dir", data_dir};
  // Any free port, unless the test chose one (to restart a daemon where its clients expect it).
  if (std::find(args.begin(), args.end(), "--listen") == args.end()) {
    all_args.insert(all_args.end(), {"--listen", "127.0.0.1:0"});
  }
  // The HTTP port too: the default one would be shared by every daemon of a parallel test run.
  if (std::find(args.begin(), args.end(), "--http-listen") == args.end()) {
    all_args.insert(all_args.end(), {"--http-listen", "127.0.0.1:0"});
  }
  all_args.insert(all_args.end(), args.begin(), args.end());
  // The log sits beside the data directory, so that it survives the daemon for the test to read.
  static int starts = 0;
  const std::string log_path = absl::StrCat(data_dir, ".fremend-", getpid(), "-", ++starts, ".log");
  const pid_t pid = SpawnBackground(FREMEND_BINARY, all_args, log_path);
  if (pid < 0) return absl::InternalError("fork failed");
  std::unique_ptr<FremendProcess> process(new FremendProcess(pid, log_path, std::move(credentials)));
  if (absl::Status serving = process->AwaitServing(); !serving.ok()) {
    return absl::Status(serving.code(), absl::StrCat(serving.message(), "\n--- fremend log ---\n", process->Log()));
  }
  return process;
}

absl::Status FremendProcess::AwaitServing() {
  // The line the daemon logs once it is ready ("fremend listening on HOST:PORT, data in ..."), with
  // the port it got for port 0.
  constexpr std::string_view kListening = "fremend listening on ";
  const auto deadline = Clock::now() + kStartTimeout;
  for (;;) {
    const std::string log = Log();
    if (const size_t at = log.find(kListening); at != std::string::npos) {
      const size_t start = at + kListening.size();
      address_ = log.substr(start, log.find(',', start) - start);
      // Logged before the line above, when the daemon has an HTTP port.
      constexpr std::string_view kHttp = "serving HTTP on ";
      if (const size_t http = log.find(kHttp); http != std::string::npos) {
        const size_t from = http + kHttp.size();
        http_address_ = log.substr(from, log.find_first_of(" \n", from) - from);
      }
      break;
    }
    if (Reap(false)) return absl::FailedPreconditionError(absl::StrCat("fremend exited with code ", exit_code_));
    if (Clock::now() > deadline) return absl::DeadlineExceededError("fremend did not say where it listens");
    std::this_thread::sleep_for(kPollInterval);
  }
  auto health = grpc::health::v1::Health::NewStub(NewChannel());
  for (;;) {
    grpc::health::v1::HealthCheckRequest request;
    grpc::health::v1::HealthCheckResponse response;
    const grpc::Status status = health->Check(CallContext({}, std::chrono::seconds(5)).get(), request, &response);
    if (status.ok() && response.status() == grpc::health::v1::HealthCheckResponse::SERVING) return absl::OkStatus();
    if (Clock::now() > deadline) {
      return absl::DeadlineExceededError(absl::StrCat("fremend at ", address_, " never became SERVING: ",
                                                      status.error_message()));
    }
    std::this_thread::sleep_for(kPollInterval);
  }
}

FremendProcess::~FremendProcess() {
  // A daemon that ended by itself while the test still held it crashed or gave up: say so with its
  // log, rather than let a later call's "cannot connect" be the only trace.
  if (running_ && Reap(false)) {
    const std::string log = Log();
    ADD_FAILURE() << "fremend (pid " << pid_ << ") ended by itself during the test, exit code " << exit_code_
                  << " (-1: a signal); the end of its log:\n"
                  << log.substr(log.size() > 4000 ? log.size() - 4000 : 0);
  }
  if (running_) Kill();
}

std::shared_ptr<grpc::Channel> FremendProcess::NewChannel() const {
  return grpc::CreateChannel(address_, credentials_);
}

std::optional<int> FremendProcess::Reap(bool block) {
  if (!running_) return exit_code_;
  int status = 0;
  const pid_t reaped = waitpid(pid_, &status, block ? 0 : WNOHANG);
  if (reaped != pid_) return std::nullopt;
  running_ = false;
  exit_code_ = ExitCodeOf(status);
  return exit_code_;
}

int FremendProcess::Stop(int signal) {
  if (!running_) return exit_code_;
  kill(pid_, signal);
  const auto deadline = Clock::now() + kStopTimeout;
  while (Clock::now() < deadline) {
    if (auto code = Reap(false)) return *code;
    std::this_thread::sleep_for(kPollInterval);
  }
  Kill();
  return -1;
}

void FremendProcess::Kill() {
  if (!running_) return;
  kill(pid_, SIGKILL);
  Reap(true);
}

std::string FremendProcess::Log() const { return ReadTextFile(log_path_); }

std::unique_ptr<grpc::ClientContext> CallContext(const std::vector<std::pair<std::string, std::string>>& metadata,
                                                 std::chrono::seconds deadline) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + deadline);
  for (const auto& [key, value] : metadata) context->AddMetadata(key, value);
  return context;
}

void DaemonTest::TearDown() {
  if (daemon_ != nullptr) StopDaemon();
}

void DaemonTest::StartDaemon(const std::vector<std::string>& args,
                             std::shared_ptr<grpc::ChannelCredentials> credentials) {
  auto started = FremendProcess::Start(data_dir(), args, std::move(credentials));
  ASSERT_TRUE(started.ok()) << started.status();
  daemon_ = *std::move(started);
}

void DaemonTest::StopDaemon() {
  ASSERT_NE(daemon_, nullptr);
  EXPECT_EQ(daemon_->Stop(), 0) << daemon_->Log();
  daemon_.reset();
}

}  // namespace fremen::testing
