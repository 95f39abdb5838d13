// `fremend --verify`: checks a data directory at rest, like fsck, instead of serving it. Every map
// the catalog lists is verified (storage/verify.h: every shard record, every log record, the
// checkpoints against the log), each shard read in a child process so that an LMDB abort on a
// damaged page is reported rather than ending the check. Nothing is written but the data
// directory's lock, which is held throughout so that no daemon starts on the directory meanwhile;
// a running daemon's lock makes it refuse (check a served map with `fremenctl check MAP`).
// Thread-compatible.
#pragma once

#include <ostream>

#include "server/daemon/config.h"

namespace fremen::server {

// Prints a report per map and a summary to `out`; returns 0 when everything verified, 1 when a
// problem was found or the directory could not be checked (the reason on `err`).
int VerifyDataDirCommand(const ServerConfig& config, std::ostream& out, std::ostream& err);

}  // namespace fremen::server
