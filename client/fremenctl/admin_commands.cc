#include "client/fremenctl/admin_commands.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

// Backups copy whole maps: the global --timeout (meant for queries) is raised to at least this.
constexpr double kMinBackupSeconds = 600;

CallOptions BackupCall() { return GlobalCallOfAtLeast(absl::Seconds(kMinBackupSeconds)); }

// The daemon's message for a bad backup directory, with what it means on this side.
absl::Status ExplainDirectory(const absl::Status& status) {
  if (absl::IsAlreadyExists(status)) {
    return absl::AlreadyExistsError(absl::StrCat(status.message(), "; pick a new directory name"));
  }
  if (absl::IsInvalidArgument(status) && absl::StrContains(status.message(), "directory")) {
    return absl::InvalidArgumentError(
        absl::StrCat(status.message(), " (a directory is relative to the daemon's backup root, config backup_dir)"));
  }
  return status;
}

}  // namespace

void RegisterBackupCommand(CLI::App& app) {
  struct Args {
    std::string map, directory;
  };
  auto a = std::make_shared<Args>();
  CLI::App* backup = app.add_subcommand("backup", "A consistent copy of a map while it keeps serving");
  backup->add_option("--map", a->map, "the map")->required();
  backup->add_option("--to", a->directory, "a new directory, relative to the daemon's backup root (config backup_dir)")
      ->required();
  backup->callback([a] {
    Client client = ConnectOrExit("backup");
    auto result = client.BackupMap(a->map, a->directory, BackupCall());
    if (!result.ok()) FailCall("backup", absl::StrCat("map ", a->map), ExplainDirectory(result.status()), a->map);
    std::printf("backed up map %s to %s (%s in %.2f s)\n", a->map.c_str(), result->path().c_str(),
                FormatBytes(result->bytes()).c_str(), result->duration_seconds());
    std::printf("restore it with `fremenctl restore --from %s --as NAME`\n", a->directory.c_str());
  });
}

void RegisterRestoreCommand(CLI::App& app) {
  struct Args {
    std::string directory, name;
  };
  auto a = std::make_shared<Args>();
  CLI::App* restore = app.add_subcommand("restore", "A backup as a new map");
  restore->add_option("--from", a->directory, "a directory written by `fremenctl backup`, relative to the backup root")
      ->required();
  restore->add_option("--as", a->name, "the new map's name (default: the backed-up map's name)");
  restore->callback([a] {
    Client client = ConnectOrExit("restore");
    auto map = client.RestoreMap(a->directory, a->name, BackupCall());
    if (!map.ok()) {
      absl::Status status = map.status();
      if (absl::IsAlreadyExists(status)) {
        status =
            absl::AlreadyExistsError(absl::StrCat(status.message(), "; restore under another name with --as NAME"));
      }
      FailCall("restore", absl::StrCat("backup ", a->directory), status);
    }
    std::printf("restored map %s from %s\n", map->name().c_str(), a->directory.c_str());
  });
}

namespace {

// The status of the daemon at `address`, as lines for people.
void PrintStatus(const std::string& address, const v1::GetServerStatusResponse& s) {
  std::printf("fremend %s at %s, up %.0f s (since %s)\n", s.version().c_str(), address.c_str(),
              s.uptime_seconds(), FormatTimestamp(s.start_time()).c_str());
  std::printf("store: %s\n", s.store_state() == v1::STORE_STATE_OPEN ? "open" : "recovering");
  std::printf("maps: %llu, states: %llu (%llu dynamic)\n", static_cast<unsigned long long>(s.map_count()),
              static_cast<unsigned long long>(s.state_count()),
              static_cast<unsigned long long>(s.dynamic_state_count()));
  std::printf("free space: %s\n", FormatBytes(s.data_dir_free_bytes()).c_str());
  std::printf("security: %s, %s\n", s.tls() ? "TLS" : "no TLS",
              s.tokens_required() ? "tokens required" : "no tokens");
  if (s.update_schedule().empty()) {
    std::printf("update schedule: none\n");
  } else {
    std::printf("update schedule: %s (%s), next %s\n", s.update_schedule().c_str(), s.update_time_zone().c_str(),
                FormatTimestamp(s.next_update_time()).c_str());
  }
  std::printf("running operations: %u\n", s.running_operations());
  for (const v1::MapFault& fault : s.failed_maps()) {
    std::printf("failed map %s: %s\n", fault.map().c_str(), fault.error().c_str());
  }
  for (const std::string& dir : s.unknown_directories()) {
    std::printf("unknown directory (no catalog record names it; left for an operator): %s\n", dir.c_str());
  }
  if (s.has_next_scrub_time()) {
    std::printf("background scrub: next pass %s\n", FormatTimestamp(s.next_scrub_time()).c_str());
  }
  for (const v1::MapScrub& scrub : s.map_scrubs()) {
    if (scrub.clean()) {
      std::printf("scrub of %s: %s, clean (%llu records)\n", scrub.map().c_str(),
                  FormatTimestamp(scrub.finish_time()).c_str(), static_cast<unsigned long long>(scrub.records()));
      continue;
    }
    std::printf("scrub of %s: %s, %llu PROBLEMS (fremenctl check %s lists them all)\n", scrub.map().c_str(),
                FormatTimestamp(scrub.finish_time()).c_str(), static_cast<unsigned long long>(scrub.problem_count()),
                scrub.map().c_str());
    for (const v1::CheckProblem& p : scrub.problems()) {
      std::printf("  %s\n", FormatCheckProblem(p).c_str());
    }
  }
  for (const v1::Operation& op : s.last_updates()) {
    std::printf("last update of %s: %s, %s\n", op.map().c_str(), FormatTimestamp(op.end_time()).c_str(),
                op.error().code() == 0 ? absl::StrCat(op.update().states_published(), " states published").c_str()
                                       : absl::StrCat("failed: ", op.error().message()).c_str());
  }
}

}  // namespace

void RegisterStatusCommand(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* status = app.add_subcommand("status", "The daemon's version, uptime, maps, schedule, last updates and scrubs");
  status->add_flag("--json", *json, "as JSON");
  status->footer(
      "With several daemons (--address A,B,C): each daemon's status in turn, then the fleet's sum\n"
      "(--json: one object per daemon, {\"daemon\": ..., \"status\": ...}); exit 1 when one does not answer.");
  status->callback([json] {
    int unreachable = 0;
    if (!NamesAFleet()) {
      const Client client = ConnectOrExit("status");
      auto s = client.GetServerStatus(GlobalCall());
      if (!s.ok()) FailCall("status", Globals().address, s.status());
      *json ? PrintJson(*s) : PrintStatus(Globals().address, *s);
      return;
    }
    const FleetStatus fleet = ConnectFleetOrExit("status").GetServerStatus(GlobalCall());
    for (const DaemonStatus& daemon : fleet.daemons) {
      if (!daemon.status.ok()) {
        ReportCall("status", daemon.address, daemon.address, daemon.status);
        ++unreachable;
        continue;
      }
      if (*json) {
        std::printf("{\"daemon\":\"%s\",\"status\":%s}\n", daemon.address.c_str(), JsonOf(daemon.server).c_str());
      } else {
        std::printf("== %s\n", daemon.address.c_str());
        PrintStatus(daemon.address, daemon.server);
      }
    }
    if (!*json) {
      const FleetStatusSummary& sum = fleet.summary;
      std::printf("== fleet: %zu of %zu daemons answered; %llu maps, %llu states, %llu running operations, %llu failed "
                  "maps; versions %s\n",
                  sum.answered, sum.daemons, static_cast<unsigned long long>(sum.map_count),
                  static_cast<unsigned long long>(sum.state_count),
                  static_cast<unsigned long long>(sum.running_operations),
                  static_cast<unsigned long long>(sum.failed_maps), absl::StrJoin(sum.versions, ", ").c_str());
    }
    if (unreachable > 0) throw CLI::RuntimeError(kExitFailure);
  });
}

}  // namespace fremen::client
