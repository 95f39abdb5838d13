// fremend's command line: --config FILE, a flag for every setting of the config table
// (--listen, --data-dir, ...: the key with '-' for '_'), --check-config, --verify, --version and
// --help.
// Settings come from the embedded defaults, then the config file, then the flags.
// Pure apart from reading the files the settings name; thread-compatible.
#pragma once

#include <optional>
#include <ostream>

#include "server/daemon/config.h"

namespace fremen::server {

// Exit codes of fremend: 0 normal stop (or help), 1 failure while starting or running, 2 bad
// command line or configuration.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadConfig = 2;

// Run the daemon with `config`, or exit with `exit_code` (help, version, --check-config, or a bad
// flag or setting — the message already written to `err`).
struct CommandLine {
  std::optional<ServerConfig> config;
  int exit_code = kExitOk;
  // --verify: check the data directory offline (server/daemon/verify_command.h) instead of serving it.
  bool verify = false;
};

CommandLine ParseCommandLine(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace fremen::server
