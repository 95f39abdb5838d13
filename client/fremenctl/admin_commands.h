// `fremenctl backup | restore | status`: copies of maps and the daemon's state.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterBackupCommand(CLI::App& app);
void RegisterRestoreCommand(CLI::App& app);
void RegisterStatusCommand(CLI::App& app);

}  // namespace fremen::client
