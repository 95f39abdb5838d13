// fremenctl bench: runs one of the load generators (client/bench/) against the daemon of the
// global options.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterBenchCommand(CLI::App& app);

}  // namespace fremen::client
