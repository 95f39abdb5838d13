#include "client/fremenctl/connection.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/fremenctl/exit_codes.h"
#include "client/lib/fleet_addresses.h"

namespace fremen::client {

namespace {

GlobalOptions& MutableGlobals() {
  static GlobalOptions options;
  return options;
}

}  // namespace

const GlobalOptions& Globals() { return MutableGlobals(); }

void AddGlobalOptions(CLI::App& app) {
  GlobalOptions& o = MutableGlobals();
  app.add_option("--address", o.address, "fremend's HOST:PORT")
      ->envname("FREMEN_ADDRESS")
      ->capture_default_str()
      ->group("Connection");
  app.add_option("--token", o.token, "bearer token (read or write) when fremend wants tokens")
      ->envname("FREMEN_TOKEN")
      ->group("Connection");
  app.add_option("--tls-ca", o.tls_ca_file, "connect with TLS, trusting the root certificates of this PEM file")
      ->check(CLI::ExistingFile)
      ->group("Connection");
  app.add_option("--timeout", o.timeout_seconds, "deadline of each call, seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->group("Connection");
  // Global options may come after the subcommand too.
  app.fallthrough();
}

CallOptions GlobalCall() { return CallOptions{.timeout = absl::Seconds(Globals().timeout_seconds)}; }

CallOptions GlobalCallOfAtLeast(absl::Duration minimum) {
  return CallOptions{.timeout = std::max(absl::Seconds(Globals().timeout_seconds), minimum)};
}

std::vector<std::string> Addresses() { return SplitAddressList(Globals().address); }

bool NamesAFleet() { return client::NamesAFleet(Addresses()); }

namespace {

// The ConnectionOptions of the global options, for `address`.
ConnectionOptions OptionsOrExit(absl::string_view command, const std::string& address) {
  const GlobalOptions& g = Globals();
  ConnectionOptions options;
  options.address = address;
  options.token = g.token;
  options.default_timeout = absl::Seconds(g.timeout_seconds);
  // A person waits at the terminal: ride out a blip (the daemon restarting), but say soon that it
  // is down rather than retrying until --timeout.
  options.retry.max_attempts = 4;
  if (!g.tls_ca_file.empty()) {
    std::ifstream in(g.tls_ca_file);
    std::ostringstream pem;
    pem << in.rdbuf();
    if (!in) FailUsage(command, absl::StrCat("--tls-ca: cannot read ", g.tls_ca_file));
    options.tls = true;
    options.tls_root_certs_pem = pem.str();
  }
  return options;
}

Client ConnectToOrExit(absl::string_view command, const std::string& address) {
  auto client = Client::Connect(OptionsOrExit(command, address));
  if (!client.ok()) FailUsage(command, client.status().message());
  return *std::move(client);
}

}  // namespace

Client ConnectOrExit(absl::string_view command) {
  const std::vector<std::string> addresses = Addresses();
  if (NamesAFleet() || addresses.empty()) {
    FailUsage(command, absl::StrCat("--address names ", addresses.size(),
                                    " daemons; this command talks to one: a daemon, or the fleet's proxy"));
  }
  return ConnectToOrExit(command, addresses[0]);
}

FleetClient ConnectFleetOrExit(absl::string_view command, const std::vector<std::string>& addresses) {
  auto fleet = FleetClient::Connect(addresses.empty() ? Addresses() : addresses, OptionsOrExit(command, ""));
  if (absl::IsInvalidArgument(fleet.status())) {
    FailUsage(command, absl::StrCat("--address: ", fleet.status().message()));
  }
  if (!fleet.ok()) FailCall(command, Globals().address, fleet.status());
  return *std::move(fleet);
}

std::string HintFor(const absl::Status& status, absl::string_view map, absl::string_view address) {
  switch (status.code()) {
    case absl::StatusCode::kNotFound:
      if (!map.empty() && absl::StrContains(status.message(), "no map named")) {
        return absl::StrCat("map \"", map, "\" does not exist on ", address, "; `fremenctl maps list` shows the maps");
      }
      return "";
    case absl::StatusCode::kUnavailable:
      return absl::StrCat("is fremend running at ", address,
                          "? Start it, or point --address (or FREMEN_ADDRESS) at it");
    case absl::StatusCode::kUnauthenticated:
      return "fremend wants a token: pass --token (or set FREMEN_TOKEN)";
    case absl::StatusCode::kPermissionDenied:
      return "this needs a write token: pass one with --token (or FREMEN_TOKEN)";
    case absl::StatusCode::kDeadlineExceeded:
      return "the call took longer than --timeout; raise it for large maps";
    default:
      return "";
  }
}

void ReportCall(absl::string_view command, absl::string_view address, absl::string_view what,
                const absl::Status& status, absl::string_view map) {
  std::fprintf(stderr, "fremenctl %s: %s: %s\n", std::string(command).c_str(), std::string(what).c_str(),
               std::string(status.message()).c_str());
  const std::string hint = HintFor(status, map, address);
  if (!hint.empty()) std::fprintf(stderr, "  %s\n", hint.c_str());
}

void FailCall(absl::string_view command, absl::string_view what, const absl::Status& status, absl::string_view map) {
  ReportCall(command, Globals().address, what, status, map);
  throw CLI::RuntimeError(kExitFailure);
}

void FailUsage(absl::string_view command, absl::string_view message) {
  std::fprintf(stderr, "fremenctl %s: %s\n", std::string(command).c_str(), std::string(message).c_str());
  throw CLI::RuntimeError(kExitUsage);
}

}  // namespace fremen::client
