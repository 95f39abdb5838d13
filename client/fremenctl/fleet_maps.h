// What the fleet-wide commands (maps list, fleet placement, update --all with several --address)
// share: every map of every daemon, asked of each daemon directly by the client library's
// FleetClient (the proxy would send a call without a map to any one of them). A daemon that does
// not answer is reported on stderr and left out, so that one daemon down does not hide the rest
// of the fleet; the caller then exits 1. A map that two daemons hold is listed once per daemon.
// Thread-compatible: one command runs at a time.
#pragma once

#include "absl/strings/string_view.h"
#include "client/lib/fleet_client.h"

namespace fremen::client {

// fleet.ListAllMaps(), each daemon that did not answer reported.
FleetMaps ListFleetOrReport(absl::string_view command, const FleetClient& fleet);

}  // namespace fremen::client
