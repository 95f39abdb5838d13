#include "client/fremenctl/fleet_maps.h"

#include "absl/strings/str_cat.h"

namespace fremen::client {

FleetMaps ListEachDaemon(absl::string_view command, const std::vector<Daemon>& daemons) {
  FleetMaps fleet;
  for (const Daemon& daemon : daemons) {
    auto maps = daemon.client.ListAllMaps(GlobalCall());
    if (!maps.ok()) {
      ReportCall(command, daemon.address, absl::StrCat("listing the maps of ", daemon.address), maps.status());
      ++fleet.unreachable;
      continue;
    }
    fleet.daemons.push_back({daemon.address, *std::move(maps)});
  }
  return fleet;
}

}  // namespace fremen::client
