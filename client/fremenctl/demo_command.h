// `fremenctl demo`: a simulated week of an office (formats/office_simulator.h) written into a
// running fremend — a grid map and a generic-state map — updated, so that a newcomer has maps to
// query at once.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterDemoCommand(CLI::App& app);

}  // namespace fremen::client
