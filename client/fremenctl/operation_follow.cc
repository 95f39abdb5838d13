#include "client/fremenctl/operation_follow.h"

#include <unistd.h>

#include <cstdio>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/progress.h"

namespace fremen::client {

namespace {

// A bar on a terminal; elsewhere a line when the figures change, at most every line interval (a log
// should not get a line per poll).
class ProgressDisplay {
 public:
  explicit ProgressDisplay(absl::Duration line_interval)
      : terminal_(isatty(STDERR_FILENO) == 1), line_interval_(line_interval) {}

  void Show(const v1::Operation& op) {
    if (terminal_) {
      std::fprintf(stderr, "\r%s\033[K", ProgressBar(op).c_str());
      if (op.done()) std::fprintf(stderr, "\n");
    } else {
      const std::string line = ProgressLine(op);
      const absl::Time now = absl::Now();
      if (line != last_line_ && (op.done() || now - last_time_ >= line_interval_)) {
        std::fprintf(stderr, "%s\n", line.c_str());
        last_line_ = line;
        last_time_ = now;
      }
    }
    std::fflush(stderr);
  }

 private:
  const bool terminal_;
  const absl::Duration line_interval_;
  std::string last_line_;
  absl::Time last_time_ = absl::InfinitePast();
};

}  // namespace

void AddFollowOptions(CLI::App* command, FollowArgs& args, const std::string& when) {
  const std::string prefix = when.empty() ? "" : when + ": ";
  command->add_option("--poll-interval", args.poll_seconds, prefix + "seconds between polls")
      ->check(CLI::Range(0.01, 60.0))
      ->capture_default_str();
  command->add_option("--line-interval", args.line_seconds, prefix + "not on a terminal, seconds between progress lines")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

void FollowOperation(const Client& client, const std::string& command, const std::string& map,
                     const std::string& name, const FollowOptions& options) {
  ProgressDisplay display(options.line_interval);
  WaitOptions wait;
  wait.poll_interval = options.poll_interval;
  wait.on_progress = [&display](const v1::Operation& o) { display.Show(o); };
  auto done = client.WaitOperation(map, name, wait, GlobalCall());
  if (!done.ok()) FailCall(command, absl::StrCat("following ", name), done.status(), map);
  const std::string summary = UpdateSummary(*done);
  if (done->error().code() != 0) {
    std::fprintf(stderr, "fremenctl %s: %s\n", command.c_str(), summary.c_str());
    throw CLI::RuntimeError(kExitFailure);
  }
  std::printf("%s\n", summary.c_str());
}

}  // namespace fremen::client
