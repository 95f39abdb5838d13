// The addresses of a fleet's daemons as people write them: a comma-separated list
// ("fremend-0.fremend:50051,fremend-1.fremend:50051") whose items may be all:HOST:PORT, which stands
// for every address HOST resolves to — a Kubernetes headless Service's name resolves to all its
// pods, so a client given all:fremend:50051 needs no change when the StatefulSet grows.
// Shared by FleetClient (fleet_client.h) and fremenctl's --address.
// Thread-safety: free functions; ResolveEvery calls getaddrinfo, which is thread-safe.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace fremen::client {

inline constexpr absl::string_view kEveryAddressPrefix = "all:";

// The items of a comma-separated list, blanks around them and empty items dropped, in order.
std::vector<std::string> SplitAddressList(absl::string_view comma_separated);

// Whether `addresses` name a fleet rather than one daemon: several, or one all:HOST:PORT.
bool NamesAFleet(const std::vector<std::string>& addresses);

// Every address HOST resolves to, as "IP:PORT" ("[IPv6]:PORT"), sorted; `host_port` is HOST:PORT
// (without all:). INVALID_ARGUMENT when it is not HOST:PORT, UNAVAILABLE when HOST does not resolve.
absl::StatusOr<std::vector<std::string>> ResolveEvery(absl::string_view host_port);

// `addresses` with each all:HOST:PORT replaced by ResolveEvery's addresses, in order; the others as
// written. INVALID_ARGUMENT when the result is empty or names an address twice.
absl::StatusOr<std::vector<std::string>> ExpandAddresses(const std::vector<std::string>& addresses);

}  // namespace fremen::client
