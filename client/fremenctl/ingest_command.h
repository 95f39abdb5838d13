// `fremenctl ingest`: observations from files into a map — `time state` files for one generic
// state, CSV files of grid cells, and directories of ROS map_server snapshots (PGM + YAML, one per
// time). See the subcommand's --help for the formats.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterIngestCommand(CLI::App& app);

}  // namespace fremen::client
