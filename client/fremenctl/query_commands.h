// `fremenctl predict | top | anomalies | stats`: what a map's model says.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterPredictCommand(CLI::App& app);
void RegisterTopCommand(CLI::App& app);
void RegisterStatesCommand(CLI::App& app);
void RegisterAnomaliesCommand(CLI::App& app);
void RegisterStatsCommand(CLI::App& app);

}  // namespace fremen::client
