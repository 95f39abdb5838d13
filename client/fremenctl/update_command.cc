#include "client/fremenctl/update_command.h"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/fleet_maps.h"
#include "client/fremenctl/operation_follow.h"
#include "client/fremenctl/progress.h"

namespace fremen::client {

namespace {

struct UpdateArgs {
  std::string map;
  bool all = false;
  bool wait = false;
  FollowArgs follow;
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
  FollowOperation(client, "update", a.map, op->name(), a.follow.options());
}

// `update --all`: the job on every map of every daemon of --address (for a nightly CronJob over a
// fleet). All are started first — each daemon queues its own — then, with --wait, followed to
// their ends one line each. A map that fails does not stop the others; the exit code says whether
// any failed, or a daemon did not answer.
void RunUpdateAll(const UpdateArgs& a) {
  const std::string command = "update --all";
  const FleetClient daemons = ConnectFleetOrExit(command);
  const FleetMaps fleet = ListFleetOrReport(command, daemons);
  struct Started {
    const FleetMember* daemon;
    v1::Operation op;
  };
  std::vector<Started> started;
  int failed = static_cast<int>(fleet.Unreachable().size());
  for (const FleetMap& held : fleet.maps) {
    const FleetMember* daemon = nullptr;
    for (const FleetMember& d : daemons.members()) {
      if (d.address == held.daemon) daemon = &d;
    }
    auto op = daemon->client.RunUpdate(held.map.name(), GlobalCall());
    if (!op.ok()) {
      ReportCall(command, held.daemon, absl::StrCat("map ", held.map.name(), " on ", held.daemon), op.status(),
                 held.map.name());
      ++failed;
      continue;
    }
    std::printf("started %s (update of %s on %s)\n", op->name().c_str(), held.map.name().c_str(),
                held.daemon.c_str());
    started.push_back({daemon, *std::move(op)});
  }
  const size_t maps = fleet.maps.size();
  std::fflush(stdout);
  size_t succeeded = started.size();
  if (a.wait) {
    succeeded = 0;
    WaitOptions wait;
    wait.poll_interval = a.follow.options().poll_interval;
    for (const Started& s : started) {
      auto done = s.daemon->client.WaitOperation(s.op.map(), s.op.name(), wait, GlobalCall());
      if (!done.ok()) {
        ReportCall(command, s.daemon->address, absl::StrCat("following ", s.op.name()), done.status(), s.op.map());
        ++failed;
        continue;
      }
      done->error().code() == 0 ? ++succeeded : ++failed;
      std::printf("%s: %s\n", s.daemon->address.c_str(), OperationLine(*done).c_str());
      std::fflush(stdout);
    }
  }
  std::printf("%s: %zu maps on %zu daemons: %zu %s, %d failed\n", command.c_str(), maps, daemons.members().size(),
              succeeded, a.wait ? "updated" : "started", failed);
  if (failed > 0) throw CLI::RuntimeError(kExitFailure);
}

}  // namespace

void RegisterUpdateCommand(CLI::App& app) {
  auto a = std::make_shared<UpdateArgs>();
  CLI::App* update = app.add_subcommand("update", "Run the update job (order selection, republication) on a map now");
  CLI::Option* map = update->add_option("--map", a->map, "the map");
  CLI::Option* all = update->add_flag(
      "--all", a->all, "every map of every daemon of --address (A,B,C: a fleet, each daemon asked directly)");
  map->excludes(all);
  update->add_flag("--wait", a->wait,
                   "follow the job to its end (a progress bar on a terminal, lines otherwise); exit 1 when it fails "
                   "or is cancelled");
  AddFollowOptions(update, a->follow, "with --wait");
  update->footer(
      "While an update of the map runs, a new request joins it: `fremenctl update --map M --wait` follows the "
      "running job.\nFor a nightly cron: fremenctl update --map M --wait || alert\n"
      "For a fleet's nightly CronJob: fremenctl update --all --wait --address all:fremend:50051 || alert");
  update->callback([a] {
    if (a->all) return RunUpdateAll(*a);
    if (a->map.empty()) FailUsage("update", "name the map with --map M, or --all for every map");
    RunUpdate(*a);
  });
}

}  // namespace fremen::client
