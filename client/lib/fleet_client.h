// Fleet-wide views for the C++ client: the maps and the status of every daemon of a fleet, asked
// of each daemon directly — through the proxy, a call that names no map (ListMaps,
// GetServerStatus) reaches whichever one daemon the proxy picks (docs/fleet.md).
//
//   auto fleet = fremen::client::FleetClient::Connect({"all:fremend:50051"}, {.token = "..."});
//   fremen::client::FleetMaps maps = fleet->ListAllMaps();
//   for (const auto& m : maps.maps) std::cout << m.map.name() << " on " << m.daemon << "\n";
//   for (const auto& d : maps.Unreachable()) std::cerr << d.address << ": " << d.status << "\n";
//
// The daemons are asked at once, one thread each, so a view takes as long as the slowest daemon,
// not their sum. A daemon that does not answer does not hide the others: its address and status
// come back beside their answers. Nothing is deduplicated: a map that two daemons hold (a move
// in progress, or a restored copy) is listed once per daemon and named in `duplicates`.
//
// ClientFor(map) is the Client of the daemon that owns a map by placement.h's consistent hash, for
// a caller that bypasses the proxy; it needs the daemons named as the proxy names them.
// Thread-safety: thread-safe, as Client.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/lib/client.h"
#include "client/lib/options.h"
#include "client/lib/placement.h"
#include "fremen/v1/admin.pb.h"
#include "fremen/v1/maps.pb.h"

namespace fremen::client {

// One daemon of the fleet and the Client that talks to it.
struct FleetMember {
  std::string address;
  Client client;
};

// How one daemon answered a fleet-wide call: OK, or the call's status (UNAVAILABLE when it is down).
struct DaemonAnswer {
  std::string address;
  absl::Status status;
};

// A map and the daemon that answered it.
struct FleetMap {
  v1::Map map;
  std::string daemon;
  // Another daemon listed a map of the same name too.
  bool duplicate = false;
};

struct FleetMaps {
  // Every map of every daemon that answered, in name order, then in the fleet's daemon order.
  std::vector<FleetMap> maps;
  // Every daemon, in the fleet's order, with how it answered.
  std::vector<DaemonAnswer> daemons;
  // The names held by more than one daemon, in name order (their FleetMaps have `duplicate`).
  std::vector<std::string> duplicates;

  // The daemons that did not answer.
  std::vector<DaemonAnswer> Unreachable() const;
};

struct DaemonStatus {
  std::string address;
  absl::Status status;                  // OK: `server` is its answer
  v1::GetServerStatusResponse server;  // empty when !status.ok()
};

// The answers of the daemons that answered, added up.
struct FleetStatusSummary {
  size_t daemons = 0;   // in the fleet
  size_t answered = 0;  // of them, those that answered
  uint64_t map_count = 0;
  uint64_t state_count = 0;
  uint64_t dynamic_state_count = 0;
  uint64_t running_operations = 0;
  uint64_t failed_maps = 0;  // maps not served or whose writes stopped, over the fleet
  // The least free space of a data directory (the daemon that fills first); 0 when none answered.
  uint64_t min_data_dir_free_bytes = 0;
  // The distinct versions the daemons run, sorted: more than one during a rolling upgrade.
  std::vector<std::string> versions;
  // The daemons still opening their maps (store_state RECOVERING).
  std::vector<std::string> recovering;
};

struct FleetStatus {
  std::vector<DaemonStatus> daemons;  // in the fleet's order
  FleetStatusSummary summary;
};

class FleetClient {
 public:
  // A Client per daemon, each with `options` (token, TLS, timeouts, retry; its address ignored).
  // `addresses` are HOST:PORT, each item possibly all:HOST:PORT (every address HOST resolves to)
  // or a comma-separated list (fleet_addresses.h). INVALID_ARGUMENT for no daemon, one named
  // twice or a bad option; UNAVAILABLE when an all: name does not resolve. Does not wait for the
  // daemons.
  static absl::StatusOr<FleetClient> Connect(const std::vector<std::string>& addresses,
                                             const ConnectionOptions& options = {});

  // In the order given (an all: name's addresses sorted, in its place).
  const std::vector<FleetMember>& members() const { return members_; }

  // Every map of every daemon (Client::ListAllMaps of each, at once).
  FleetMaps ListAllMaps(const CallOptions& call = {}) const;
  // Each daemon's status, and their sum.
  FleetStatus GetServerStatus(const CallOptions& call = {}) const;

  // The Client of the daemon that owns `map` by the proxy's consistent hash (placement.h). The
  // ring hashes the proxy's `server` strings, so the addresses must be written exactly as the
  // proxy's configuration writes them: FAILED_PRECONDITION for a fleet given as all:HOST:PORT,
  // whose resolved IPs the proxy does not hash. REQUIRES: map is not empty.
  absl::StatusOr<Client> ClientFor(absl::string_view map) const;

 private:
  FleetClient(std::vector<FleetMember> members, std::optional<Placement> placement)
      : members_(std::move(members)), placement_(std::move(placement)) {}

  std::vector<FleetMember> members_;
  std::optional<Placement> placement_;  // nullopt when an address was all:HOST:PORT
};

}  // namespace fremen::client
