// `fremenctl check MAP`: verifies a served map's files, like fsck (AdminService.CheckMap): one line
// per problem, a summary, exit code 0 when clean and 1 when a problem was found.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterCheckCommand(CLI::App& app);

}  // namespace fremen::client
