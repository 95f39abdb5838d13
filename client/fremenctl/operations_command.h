// `fremenctl operations list|wait|cancel`: the daemon's long-running operations (update jobs,
// whether started by `fremenctl update` or by the schedule). `wait` follows one to its end as
// `update --wait` does (exit 1 when it fails or is cancelled); `cancel` asks one to stop (a queued
// job ends at once, a running one before it publishes, a publishing one finishes).
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterOperationsCommand(CLI::App& app);

}  // namespace fremen::client
