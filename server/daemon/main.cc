// fremend: the fremen map database daemon. main() reads the configuration, sets up logging, starts
// the daemon step by step (server/daemon/daemon.h) and waits for SIGTERM or SIGINT to stop it.
//
// Exit codes (server/daemon/command_line.h): 0 stopped by a signal with every acknowledged write flushed
// (or --help, --version, --check-config, a clean --verify), 1 failure while starting or stopping
// (or problems found by --verify), 2 bad command line or configuration.
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>

#include "absl/synchronization/mutex.h"
#include "server/daemon/command_line.h"
#include "server/daemon/daemon.h"
#include "server/rpc/logging.h"
#include "server/daemon/verify_command.h"

namespace {

// SIGTERM and SIGINT, blocked in every thread (threads inherit the mask, so this runs before any
// thread starts) and taken synchronously by sigwait: no handler runs at an arbitrary moment.
sigset_t TerminationSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  return signals;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace fremen::server;
  CommandLine command_line = ParseCommandLine(argc, argv, std::cout, std::cerr);
  if (!command_line.config) return command_line.exit_code;
  if (command_line.verify) return VerifyDataDirCommand(*command_line.config, std::cout, std::cerr);

  // Debian's libabsl is built with its debug checks: every absl::Mutex lock (gRPC takes several a
  // call) records lock order in a global graph under a spin lock: 3.3% of the daemon's instructions
  // under batched Predicts (callgrind, docs/performance.md#batched-predict). A debug aid, not the
  // daemon's job; the unit tests keep it.
  absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);
  const sigset_t signals = TerminationSignals();
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  SetUpLogging(command_line.config->log_level);
  const auto log = spdlog::get(kDaemonLogger);

  int exit_code = kExitOk;
  {
    Daemon daemon(*std::move(command_line.config));
    if (absl::Status started = daemon.Start(); !started.ok()) {
      log->critical("cannot start: {}", std::string(started.message()));
      (void)daemon.Stop();
      exit_code = kExitFailure;
    } else {
      // A signal that came during start (e.g. a long recovery) is pending and returns at once.
      int signal = 0;
      sigwait(&signals, &signal);
      log->info("{}: shutting down", signal == SIGTERM ? "SIGTERM" : "SIGINT");
      if (absl::Status stopped = daemon.Stop(); !stopped.ok()) exit_code = kExitFailure;
    }
  }
  spdlog::shutdown();
  return exit_code;
}
