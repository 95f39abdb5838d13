// A guard against LMDB aborting the process on a damaged file.
//
// LMDB trusts its pages: on some damaged ones (a zeroed page in a tree, a page number past the end of the file) it fails
// an assertion and calls abort(), or touches memory past the mapped file (SIGBUS) — taking down every map of the
// daemon, with only LMDB's assertion text naming no file. ProbeEnvironments walks the files in a forked child instead:
// the child opens each environment read-only (no lock file), walks every page a reader or writer will reach — the free
// list, the main database, every named database and every record, touching each value's pages — and exits. A child that
// dies or reports an LMDB error marks the file damaged; the parent only reads a pipe and waits. The cost is one pass
// over the mapped files (page cache), which the later load repeats.
//
// The child runs only LMDB's C functions, write() and _exit() (LMDB's own assertion printing, which takes stdio's lock,
// is replaced by a callback that writes to the pipe), so forking a process that has other threads (gRPC's) is safe:
// nothing the child calls needs a lock another thread may hold, and glibc keeps malloc usable in a forked child.
//
// Thread-safety: a pure function; may be called from any thread (each call forks its own child).
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/time/time.h"

namespace fremen::storage {

struct ProbeOptions {
  // The child is killed, and the file reported damaged, when the walk takes longer: LMDB may loop on a damaged page as
  // well as abort. Generous, as the walk reads files that may not be cached. Default: 10 minutes.
  absl::Duration timeout = absl::Minutes(10);
};

// Walks the LMDB environments in `dirs` (directories holding data.mdb; a directory without one is skipped: a new
// environment). OK when every walk ended normally; DataLoss naming the file ("<dir>/data.mdb is damaged: LMDB aborted
// reading it (signal 6): <LMDB's assertion>") when one did not; Unavailable when no child could be forked (nothing is
// known about the files).
absl::Status ProbeEnvironments(const std::vector<std::string>& dirs, const ProbeOptions& options = {});

}  // namespace fremen::storage
