// Following an operation to its end, as `fremenctl update --wait` and `fremenctl operations wait`
// do: progress on stderr (a bar redrawn in place on a terminal, plain lines otherwise, at most one
// per line interval), then the summary on stdout; a job that failed or was cancelled prints its
// summary on stderr and exits 1 (kExitFailure), so that a cron job can alert on it.
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "absl/time/time.h"
#include "client/lib/client.h"

namespace fremen::client {

struct FollowOptions {
  absl::Duration poll_interval = absl::Milliseconds(500);
  // Not on a terminal: the least time between two progress lines.
  absl::Duration line_interval = absl::Seconds(10);
};

// FollowOptions as the command line gives them, in seconds.
struct FollowArgs {
  double poll_seconds = 0.5;
  double line_seconds = 10;
  FollowOptions options() const {
    return {absl::Seconds(poll_seconds), absl::Seconds(line_seconds)};
  }
};

// Adds --poll-interval and --line-interval to `command`; `when` opens their help ("with --wait").
void AddFollowOptions(CLI::App* command, FollowArgs& args, const std::string& when = "");

// `command` names the fremenctl command in error messages ("update", "operations wait").
void FollowOperation(const Client& client, const std::string& command, const std::string& map,
                     const std::string& name, const FollowOptions& options);

}  // namespace fremen::client
