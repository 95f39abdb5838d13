// `fremenctl export | import`: a map's copy as a file, for backups to another machine and moves by
// hand (docs/fleet.md, "Moving a map"). The file is ExportMap's stream as it came — header, data
// chunks with their checksums, trailer — each message length-delimited after a first line
// naming the format, so that `import` sends it unchanged and the daemon checks every chunk.
#pragma once

#include "CLI/CLI.hpp"
#include "client/lib/options.h"

namespace fremen::client {

void RegisterExportCommand(CLI::App& app);
void RegisterImportCommand(CLI::App& app);

// The global options' call, with a deadline long enough to copy a whole map (at least an hour).
CallOptions TransferCall();

}  // namespace fremen::client
