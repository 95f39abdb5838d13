#include "client/fremenctl/operations_command.h"

#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/operation_follow.h"
#include "client/fremenctl/print.h"
#include "client/fremenctl/progress.h"

namespace fremen::client {

namespace {

struct ListArgs {
  std::string map;
  bool running = false;
  bool json = false;
};

void List(const ListArgs& a) {
  Client client = ConnectOrExit("operations list");
  std::string token;
  do {
    auto page = client.ListOperations(a.map, a.running, 0, token, GlobalCall());
    if (!page.ok()) FailCall("operations list", a.map.empty() ? "the daemon" : absl::StrCat("map ", a.map),
                             page.status(), a.map);
    for (const v1::Operation& op : page->operations) {
      if (a.json) {
        PrintJson(op);
      } else {
        std::printf("%s\n", OperationLine(op).c_str());
      }
    }
    token = page->next_page_token;
  } while (!token.empty());
}

// The operation NAME of map --map: both are needed, the map to route the call to its daemon.
struct OperationArgs {
  std::string name;
  std::string map;
};

void AddOperationArgs(CLI::App* command, OperationArgs& a) {
  command->add_option("name", a.name, "the operation, as `fremenctl operations list` shows it (operations/…)")
      ->required();
  command->add_option("--map", a.map, "the map it works on")->required();
}

}  // namespace

void RegisterOperationsCommand(CLI::App& app) {
  CLI::App* operations =
      app.add_subcommand("operations", "List, follow and cancel the daemon's long-running operations (update jobs)");
  operations->require_subcommand(1);

  auto list_args = std::make_shared<ListArgs>();
  CLI::App* list = operations->add_subcommand("list", "Operations, newest last: running, queued and recently finished");
  list->add_option("--map", list_args->map, "only this map's (default: every map of the daemon)");
  list->add_flag("--running", list_args->running, "only those not yet done");
  list->add_flag("--json", list_args->json, "each operation as one JSON object");
  list->callback([list_args] { List(*list_args); });

  struct WaitArgs : OperationArgs {
    FollowArgs follow;
  };
  auto wait_args = std::make_shared<WaitArgs>();
  CLI::App* wait = operations->add_subcommand("wait", "Follow an operation to its end; exit 1 when it failed or was cancelled");
  AddOperationArgs(wait, *wait_args);
  AddFollowOptions(wait, wait_args->follow);
  wait->callback([wait_args] {
    Client client = ConnectOrExit("operations wait");
    FollowOperation(client, "operations wait", wait_args->map, wait_args->name, wait_args->follow.options());
  });

  auto cancel_args = std::make_shared<OperationArgs>();
  CLI::App* cancel = operations->add_subcommand("cancel", "Ask an operation to stop");
  AddOperationArgs(cancel, *cancel_args);
  cancel->footer(
      "A queued update ends at once, a running one before it publishes; one that is publishing runs to its end\n"
      "(its publication is one record of the map's log). `fremenctl operations wait` tells how it ended.");
  cancel->callback([cancel_args] {
    Client client = ConnectOrExit("operations cancel");
    auto op = client.CancelOperation(cancel_args->map, cancel_args->name, GlobalCall());
    if (!op.ok()) FailCall("operations cancel", cancel_args->name, op.status(), cancel_args->map);
    std::printf("%s\n", OperationLine(*op).c_str());
  });
}

}  // namespace fremen::client
