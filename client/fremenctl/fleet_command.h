// `fremenctl fleet placement`: which daemon of a fleet holds each map, as the proxy computes it
// (client/lib/placement.h, docs/fleet.md).
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterFleetCommand(CLI::App& app);

}  // namespace fremen::client
