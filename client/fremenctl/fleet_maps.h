// What the fleet-wide commands (maps list, fleet placement, update --all with several --address)
// share: every map of every daemon, asked of each daemon directly — the proxy would send a call
// without a map to any one of them. A daemon that does not answer is reported and left out, so
// that one daemon down does not hide the rest of the fleet; the caller then exits 1.
// Thread-compatible: one command runs at a time.
#pragma once

#include <string>
#include <vector>

#include "absl/strings/string_view.h"
#include "client/fremenctl/connection.h"
#include "fremen/v1/maps.pb.h"

namespace fremen::client {

struct DaemonMaps {
  std::string address;
  std::vector<v1::Map> maps;
};

struct FleetMaps {
  std::vector<DaemonMaps> daemons;  // the daemons that answered, in --address order
  int unreachable = 0;              // daemons that did not (each reported on stderr)
};

FleetMaps ListEachDaemon(absl::string_view command, const std::vector<Daemon>& daemons);

}  // namespace fremen::client
