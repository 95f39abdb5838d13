// `fremenctl eval`: the offline accuracy evaluation of the FreMEn model on `time state` files.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

// Adds the `eval` subcommand to `app`. When it runs, it prints one line per order; on bad input it
// reports the file and line and throws CLI::RuntimeError(kExitFailure) (see exit_codes.h), which
// main() turns into the exit code.
void RegisterEvalCommand(CLI::App& app);

}  // namespace fremen::client
