// `fremenctl fleet placement [--daemons A,B,C] [--map M]... [--http H1,H2,H3]`.
//
// With --map: the owner of each named map, computed here without asking anyone (the ring of
// client/lib/placement.h, nginx's `hash $http_x_fremen_map consistent` over the same server
// strings). Without: every map the daemons hold (asked of each), with its owner and the daemon
// that holds it; a map held elsewhere than its owner is MISPLACED — the proxy would send its calls
// to a daemon that does not have it. Exit 1 then, or when a daemon does not answer, so that a
// script can check a fleet.
//
// --http names each daemon's HTTP port (JSON API, dashboard) in the order of --daemons. The proxy
// routes an HTTP request by the gRPC ring's choice (deploy/nginx/fremen.conf), so a map's HTTP
// owner is the same daemon, at this address.
#include "client/fremenctl/fleet_command.h"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/fleet_maps.h"
#include "client/lib/fleet_addresses.h"
#include "client/fremenctl/fleet_move.h"
#include "client/lib/placement.h"

namespace fremen::client {

namespace {

struct PlacementArgs {
  std::string daemons;  // empty: --address
  std::vector<std::string> maps;
  std::string http;
};

void RunPlacement(const PlacementArgs& a) {
  const std::string command = "fleet placement";
  const std::vector<std::string> names = a.daemons.empty() ? Addresses() : SplitAddressList(a.daemons);
  for (const std::string& name : names) {
    if (absl::StartsWith(name, kEveryAddressPrefix)) {
      FailUsage(command,
                absl::StrCat("placement hashes the proxy's server strings: name the daemons one by one, not ", name));
    }
  }
  auto placement = Placement::Create(names);
  if (!placement.ok()) FailUsage(command, absl::StrCat("--daemons: ", placement.status().message()));
  const std::vector<std::string> http = SplitAddressList(a.http);
  if (!http.empty() && http.size() != names.size()) {
    FailUsage(command, absl::StrCat("--http names ", http.size(), " addresses for ", names.size(),
                                    " daemons; give one per daemon, in the same order"));
  }
  const auto http_of = [&](const std::string& map) {
    return http.empty() ? std::string() : absl::StrCat(" ", http[placement->OwnerIndex(map)]);
  };
  const std::string http_header = http.empty() ? "" : " HTTP";

  if (!a.maps.empty()) {
    std::printf("MAP OWNER%s\n", http_header.c_str());
    for (const std::string& map : a.maps) {
      std::printf("%s %s%s\n", map.c_str(), placement->Owner(map).c_str(), http_of(map).c_str());
    }
    return;
  }

  const FleetMaps fleet = ListFleetOrReport(command, ConnectFleetOrExit(command, names));
  int misplaced = 0;
  std::printf("MAP OWNER%s HELD-BY\n", http_header.c_str());
  for (const FleetMap& held : fleet.maps) {
    const std::string& owner = placement->Owner(held.map.name());
    const bool placed = owner == held.daemon;
    if (!placed) ++misplaced;
    std::printf("%s %s%s %s%s\n", held.map.name().c_str(), owner.c_str(), http_of(held.map.name()).c_str(),
                held.daemon.c_str(), placed ? "" : " MISPLACED");
  }
  if (misplaced > 0) {
    std::fprintf(stderr,
                 "fremenctl %s: %d maps are held by a daemon that is not their owner; the proxy sends their calls "
                 "to the owner, which does not have them\n",
                 command.c_str(), misplaced);
  }
  if (misplaced > 0 || !fleet.Unreachable().empty()) throw CLI::RuntimeError(kExitFailure);
}

}  // namespace

void RegisterFleetCommand(CLI::App& app) {
  CLI::App* fleet = app.add_subcommand("fleet", "A fleet of daemons behind a proxy: which daemon holds which map, moving maps");
  fleet->require_subcommand(1);
  auto a = std::make_shared<PlacementArgs>();
  CLI::App* placement = fleet->add_subcommand(
      "placement", "The daemon that owns each map, as the proxy's consistent hash on x-fremen-map places it");
  placement->add_option("--daemons", a->daemons,
                        "the fleet's daemons, HOST:PORT,...: exactly the proxy's `server` strings "
                        "(default: --address)");
  placement->add_option("--map", a->maps, "a map (may repeat); without, every map the daemons hold, asked of each");
  placement->add_option("--http", a->http,
                        "each daemon's HTTP address, in the order of --daemons: adds an HTTP column");
  placement->footer(
      "Without --map, exit 1 when a map is held by a daemon that is not its owner (MISPLACED) or a daemon does not "
      "answer.\nThe names must be the proxy's server strings exactly: nginx hashes the string, port included "
      "(docs/fleet.md).");
  placement->callback([a] { RunPlacement(*a); });
  RegisterFleetMoveCommands(*fleet);
}

}  // namespace fremen::client
