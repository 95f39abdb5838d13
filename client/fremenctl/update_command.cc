#include "client/fremenctl/update_command.h"

#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/progress.h"

namespace fremen::client {

namespace {

struct UpdateArgs {
  std::string map;
  bool wait = false;
  double poll_seconds = 0.5;
  double line_seconds = 10;
};

// Shows progress on stderr: redraws a bar on a terminal; elsewhere prints a line when the figures
// change, at most every `line_interval` (a log should not get a line per poll).
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

void RunUpdate(const UpdateArgs& a) {
  Client client = ConnectOrExit("update");
  auto op = client.RunUpdate(a.map, GlobalCall());
  if (!op.ok()) FailCall("update", absl::StrCat("map ", a.map), op.status(), a.map);
  if (!a.wait) {
    std::printf("started %s (update of %s); follow it with `fremenctl update --map %s --wait`\n", op->name().c_str(),
                a.map.c_str(), a.map.c_str());
    return;
  }
  ProgressDisplay display(absl::Seconds(a.line_seconds));
  WaitOptions wait;
  wait.poll_interval = absl::Seconds(a.poll_seconds);
  wait.on_progress = [&display](const v1::Operation& o) { display.Show(o); };
  auto done = client.WaitOperation(a.map, op->name(), wait, GlobalCall());
  if (!done.ok()) FailCall("update", absl::StrCat("following ", op->name()), done.status(), a.map);
  const std::string summary = UpdateSummary(*done);
  if (done->error().code() != 0) {
    std::fprintf(stderr, "fremenctl update: %s\n", summary.c_str());
    throw CLI::RuntimeError(kExitFailure);
  }
  std::printf("%s\n", summary.c_str());
}

}  // namespace

void RegisterUpdateCommand(CLI::App& app) {
  auto a = std::make_shared<UpdateArgs>();
  CLI::App* update = app.add_subcommand("update", "Run the update job (order selection, republication) on a map now");
  update->add_option("--map", a->map, "the map")->required();
  update->add_flag("--wait", a->wait,
                   "follow the job to its end (a progress bar on a terminal, lines otherwise); exit 1 when it fails "
                   "or is cancelled");
  update->add_option("--poll-interval", a->poll_seconds, "with --wait: seconds between polls")
      ->check(CLI::Range(0.01, 60.0))
      ->capture_default_str();
  update->add_option("--line-interval", a->line_seconds, "with --wait, not on a terminal: seconds between lines")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  update->footer(
      "While an update of the map runs, a new request joins it: `fremenctl update --map M --wait` follows the "
      "running job.\nFor a nightly cron: fremenctl update --map M --wait || alert");
  update->callback([a] { RunUpdate(*a); });
}

}  // namespace fremen::client
