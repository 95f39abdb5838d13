#include "client/fremenctl/update_command.h"

#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/operation_follow.h"

namespace fremen::client {

namespace {

struct UpdateArgs {
  std::string map;
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

}  // namespace

void RegisterUpdateCommand(CLI::App& app) {
  auto a = std::make_shared<UpdateArgs>();
  CLI::App* update = app.add_subcommand("update", "Run the update job (order selection, republication) on a map now");
  update->add_option("--map", a->map, "the map")->required();
  update->add_flag("--wait", a->wait,
                   "follow the job to its end (a progress bar on a terminal, lines otherwise); exit 1 when it fails "
                   "or is cancelled");
  AddFollowOptions(update, a->follow, "with --wait");
  update->footer(
      "While an update of the map runs, a new request joins it: `fremenctl update --map M --wait` follows the "
      "running job.\nFor a nightly cron: fremenctl update --map M --wait || alert");
  update->callback([a] { RunUpdate(*a); });
}

}  // namespace fremen::client
