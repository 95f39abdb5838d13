// `fremenctl salvage MAP [--to NEW]`: salvages a damaged map into a new one (AdminService.SalvageMap):
// one line per loss, a line per shard, a summary; exit code 0 once the new map serves.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterSalvageCommand(CLI::App& app);

}  // namespace fremen::client
