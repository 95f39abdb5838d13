#include "client/fremenctl/fleet_maps.h"

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"

namespace fremen::client {

FleetMaps ListFleetOrReport(absl::string_view command, const FleetClient& fleet) {
  FleetMaps maps = fleet.ListAllMaps(GlobalCall());
  for (const DaemonAnswer& daemon : maps.Unreachable()) {
    ReportCall(command, daemon.address, absl::StrCat("listing the maps of ", daemon.address), daemon.status);
  }
  return maps;
}

}  // namespace fremen::client
