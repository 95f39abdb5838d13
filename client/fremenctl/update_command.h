// `fremenctl update --map M [--wait]`: runs the update job (order selection and republication) on a
// map now; with --wait follows it to the end with a progress bar (plain lines when not on a
// terminal) and exits non-zero when it fails or is cancelled, so that an external cron can drive it.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterUpdateCommand(CLI::App& app);

}  // namespace fremen::client
