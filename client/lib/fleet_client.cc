#include "client/lib/fleet_client.h"

#include <algorithm>
#include <map>
#include <set>
#include <thread>
#include <tuple>
#include <utility>

#include "absl/strings/match.h"
#include "client/lib/fleet_addresses.h"

namespace fremen::client {

namespace {

// Runs ask(i) for every member i at once, one thread each, and waits for all.
template <typename Ask>
void AskEach(size_t count, const Ask& ask) {
  std::vector<std::thread> threads;
  threads.reserve(count);
  for (size_t i = 0; i < count; ++i) threads.emplace_back([&ask, i] { ask(i); });
  for (std::thread& t : threads) t.join();
}

}  // namespace

std::vector<DaemonAnswer> FleetMaps::Unreachable() const {
  std::vector<DaemonAnswer> unreachable;
  for (const DaemonAnswer& d : daemons) {
    if (!d.status.ok()) unreachable.push_back(d);
  }
  return unreachable;
}

absl::StatusOr<FleetClient> FleetClient::Connect(const std::vector<std::string>& addresses,
                                                 const ConnectionOptions& options) {
  std::vector<std::string> written;
  bool resolved = false;
  for (const std::string& item : addresses) {
    for (std::string& address : SplitAddressList(item)) {
      resolved = resolved || absl::StartsWith(address, kEveryAddressPrefix);
      written.push_back(std::move(address));
    }
  }
  auto expanded = ExpandAddresses(written);
  if (!expanded.ok()) return expanded.status();
  std::vector<FleetMember> members;
  for (const std::string& address : *expanded) {
    ConnectionOptions own = options;
    own.address = address;
    auto client = Client::Connect(std::move(own));
    if (!client.ok()) return client.status();
    members.push_back({address, *std::move(client)});
  }
  std::optional<Placement> placement;
  if (!resolved) {
    auto ring = Placement::Create(*expanded);
    if (!ring.ok()) return ring.status();
    placement.emplace(*std::move(ring));
  }
  return FleetClient(std::move(members), std::move(placement));
}

FleetMaps FleetClient::ListAllMaps(const CallOptions& call) const {
  std::vector<absl::StatusOr<std::vector<v1::Map>>> answers(members_.size(), std::vector<v1::Map>());
  AskEach(members_.size(), [&](size_t i) { answers[i] = members_[i].client.ListAllMaps(call); });

  FleetMaps fleet;
  std::vector<std::pair<FleetMap, size_t>> rows;  // with the daemon's index, for the order
  for (size_t i = 0; i < members_.size(); ++i) {
    fleet.daemons.push_back({members_[i].address, answers[i].status()});
    if (!answers[i].ok()) continue;
    for (v1::Map& map : *answers[i]) rows.push_back({FleetMap{std::move(map), members_[i].address}, i});
  }
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first.map.name(), a.second) < std::tie(b.first.map.name(), b.second);
  });
  std::map<std::string, int> held;
  for (const auto& [row, daemon] : rows) ++held[row.map.name()];
  for (auto& [row, daemon] : rows) {
    row.duplicate = held[row.map.name()] > 1;
    fleet.maps.push_back(std::move(row));
  }
  for (const auto& [name, count] : held) {
    if (count > 1) fleet.duplicates.push_back(name);
  }
  return fleet;
}

FleetStatus FleetClient::GetServerStatus(const CallOptions& call) const {
  std::vector<absl::StatusOr<v1::GetServerStatusResponse>> answers(members_.size(), v1::GetServerStatusResponse());
  AskEach(members_.size(), [&](size_t i) { answers[i] = members_[i].client.GetServerStatus(call); });

  FleetStatus fleet;
  FleetStatusSummary& sum = fleet.summary;
  sum.daemons = members_.size();
  std::set<std::string> versions;
  for (size_t i = 0; i < members_.size(); ++i) {
    DaemonStatus d{members_[i].address, answers[i].status(), {}};
    if (answers[i].ok()) {
      d.server = *std::move(answers[i]);
      const v1::GetServerStatusResponse& s = d.server;
      sum.min_data_dir_free_bytes =
          sum.answered == 0 ? s.data_dir_free_bytes() : std::min(sum.min_data_dir_free_bytes, s.data_dir_free_bytes());
      ++sum.answered;
      sum.map_count += s.map_count();
      sum.state_count += s.state_count();
      sum.dynamic_state_count += s.dynamic_state_count();
      sum.running_operations += s.running_operations();
      sum.failed_maps += s.failed_maps_size();
      versions.insert(s.version());
      if (s.store_state() == v1::STORE_STATE_RECOVERING) sum.recovering.push_back(d.address);
    }
    fleet.daemons.push_back(std::move(d));
  }
  sum.versions.assign(versions.begin(), versions.end());
  return fleet;
}

absl::StatusOr<Client> FleetClient::ClientFor(absl::string_view map) const {
  if (!placement_.has_value()) {
    return absl::FailedPreconditionError(
        "the fleet was named by all:HOST:PORT; placement hashes the proxy's server strings, so name the daemons "
        "one by one, as the proxy does");
  }
  return members_[placement_->OwnerIndex(map)].client;
}

}  // namespace fremen::client
