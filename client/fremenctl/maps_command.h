// `fremenctl maps create|list|get|delete`: the maps of a fremend.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterMapsCommand(CLI::App& app);

}  // namespace fremen::client
