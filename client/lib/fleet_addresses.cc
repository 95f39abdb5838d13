#include "client/lib/fleet_addresses.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <set>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace fremen::client {

std::vector<std::string> SplitAddressList(absl::string_view comma_separated) {
  std::vector<std::string> addresses;
  for (absl::string_view a : absl::StrSplit(comma_separated, ',', absl::SkipWhitespace())) {
    addresses.emplace_back(absl::StripAsciiWhitespace(a));
  }
  return addresses;
}

bool NamesAFleet(const std::vector<std::string>& addresses) {
  return addresses.size() > 1 || (addresses.size() == 1 && absl::StartsWith(addresses[0], kEveryAddressPrefix));
}

absl::StatusOr<std::vector<std::string>> ResolveEvery(absl::string_view host_port) {
  const size_t colon = host_port.rfind(':');
  if (colon == absl::string_view::npos || colon == 0) {
    return absl::InvalidArgumentError(absl::StrCat(kEveryAddressPrefix, host_port, ": expected all:HOST:PORT"));
  }
  const std::string host(host_port.substr(0, colon)), port(host_port.substr(colon + 1));
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (const int error = getaddrinfo(host.c_str(), port.c_str(), &hints, &found); error != 0) {
    return absl::UnavailableError(absl::StrCat("cannot resolve ", host, ": ", gai_strerror(error)));
  }
  std::set<std::string> addresses;
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    char text[INET6_ADDRSTRLEN] = {};
    if (a->ai_family == AF_INET) {
      inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(a->ai_addr)->sin_addr, text, sizeof text);
      addresses.insert(absl::StrCat(text, ":", port));
    } else if (a->ai_family == AF_INET6) {
      inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(a->ai_addr)->sin6_addr, text, sizeof text);
      addresses.insert(absl::StrCat("[", text, "]:", port));
    }
  }
  freeaddrinfo(found);
  return std::vector<std::string>(addresses.begin(), addresses.end());
}

absl::StatusOr<std::vector<std::string>> ExpandAddresses(const std::vector<std::string>& addresses) {
  std::vector<std::string> expanded;
  std::set<std::string> seen;
  const auto add = [&](const std::string& address) -> absl::Status {
    if (!seen.insert(address).second) {
      return absl::InvalidArgumentError(absl::StrCat("daemon ", address, " is named twice"));
    }
    expanded.push_back(address);
    return absl::OkStatus();
  };
  for (const std::string& address : addresses) {
    if (!absl::StartsWith(address, kEveryAddressPrefix)) {
      if (absl::Status added = add(address); !added.ok()) return added;
      continue;
    }
    auto every = ResolveEvery(absl::string_view(address).substr(kEveryAddressPrefix.size()));
    if (!every.ok()) return every.status();
    for (const std::string& resolved : *every) {
      if (absl::Status added = add(resolved); !added.ok()) return added;
    }
  }
  if (expanded.empty()) return absl::InvalidArgumentError("no daemon named");
  return expanded;
}

}  // namespace fremen::client
