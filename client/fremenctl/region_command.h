// `fremenctl region`: the predicted map of a box of a grid at a time, exported as a nav2/map_server
// PGM + YAML pair (for the ROS navigation stack) and as a PNG picture of p.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterRegionCommand(CLI::App& app);

}  // namespace fremen::client
