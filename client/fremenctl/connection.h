// What every fremenctl command that talks to fremend shares: the global options (--address,
// --token, --tls-ca, --timeout, with FREMEN_ADDRESS and FREMEN_TOKEN from the environment), the
// client made from them, and one way to report a failed call — the daemon's message and a hint
// saying what to fix (start the daemon, pass a token, `fremenctl maps list`, ...) — ending the
// command with kExitFailure.
//
// Subcommands register themselves with AddGlobalOptions' app; their callbacks run after parsing,
// when the global options hold their values. Thread-compatible: one command runs at a time.
#pragma once

#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "client/lib/client.h"
#include "client/lib/fleet_client.h"

namespace fremen::client {

struct GlobalOptions {
  // One HOST:PORT, or several separated by commas: the daemons of a fleet, for the commands that
  // look at all of them (maps list, status, update --all, fleet placement). all:HOST:PORT stands
  // for every address HOST resolves to (a Kubernetes headless Service names every pod so).
  std::string address = "127.0.0.1:50051";
  std::string token;
  // PEM file of the root certificates that sign fremend's certificate; set = use TLS.
  std::string tls_ca_file;
  // Per-call deadline, seconds.
  double timeout_seconds = 30;
};

// The options parsed by AddGlobalOptions (defaults until then).
const GlobalOptions& Globals();

// Adds the global options to `app`; they may also follow the subcommand (`fremenctl maps list
// --address host:port`).
void AddGlobalOptions(CLI::App& app);

// The addresses of --address, in order, as written (all:HOST:PORT not resolved).
std::vector<std::string> Addresses();
// Whether --address names a fleet: several addresses, or an all:HOST:PORT (fleet_addresses.h).
bool NamesAFleet();

// A client for the global options. On bad options (an unreadable --tls-ca) reports and exits; so
// does a --address naming several daemons (this command talks to one: a daemon or the proxy).
Client ConnectOrExit(absl::string_view command);

// A FleetClient of --address's daemons (or of `addresses` when not empty; all:HOST:PORT resolved,
// exit 1 when that fails), each with the global options' token, TLS and timeout.
FleetClient ConnectFleetOrExit(absl::string_view command, const std::vector<std::string>& addresses = {});

// The per-call options of the global --timeout.
CallOptions GlobalCall();
// The same with the timeout raised to at least `minimum`: calls that copy whole maps (the global
// --timeout is meant for queries).
CallOptions GlobalCallOfAtLeast(absl::Duration minimum);

// Reports on stderr — "fremenctl COMMAND: WHAT: MESSAGE" and a hint for the status code — and ends
// the command with kExitFailure (throws CLI::RuntimeError). `map`, when set, is the map the call
// was about: NOT_FOUND then says that it does not exist.
[[noreturn]] void FailCall(absl::string_view command, absl::string_view what, const absl::Status& status,
                           absl::string_view map = "");
// The same report without ending the command (a fleet command goes on with the other daemons);
// `address` is the daemon the call went to.
void ReportCall(absl::string_view command, absl::string_view address, absl::string_view what,
                const absl::Status& status, absl::string_view map = "");
// Reports a bad command line (an argument that CLI11 cannot check alone) and ends with kExitUsage.
[[noreturn]] void FailUsage(absl::string_view command, absl::string_view message);

// A hint for `status`, or "" (exposed for tests).
std::string HintFor(const absl::Status& status, absl::string_view map, absl::string_view address);

}  // namespace fremen::client
