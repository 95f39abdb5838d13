// Running a piece of file reading in a forked child process, so that LMDB's abort on a damaged
// page (mdb_assert) ends the child rather than the caller: the verifier (storage/verify.h) and the
// salvage (storage/salvage.h) read damaged shards this way.
//
// The child gets the write end of a pipe and no other descriptor of the parent (so that a child
// forked by another thread meanwhile cannot hold this pipe open); the parent is handed what it
// writes as it arrives, then reaps it. The child must only read files, decode and write to the pipe
// (no logging, no locks other threads of the parent could hold at the fork); as `child` returns it
// _exits. A child still running at the caller's deadline is killed, and the caller is told where it
// was waiting: whatever blocks it, the caller's thread and the call it serves are not held.
// Thread-safety: may be called from any thread.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace fremen::storage {

// How an isolated child ended.
struct ChildExit {
  int signal = 0;     // the signal that killed it (SIGABRT for an LMDB abort); 0 when it exited
  int exit_code = 0;  // its exit code when it exited: 0 when `child` returned true

  bool ok() const { return signal == 0 && exit_code == 0; }
};

// Forks; in the child runs child(fd) and _exits 0 when it returns true (3 otherwise); in the parent
// calls on_bytes with every chunk read from the pipe until the child closes it, then reaps the child.
// Unavailable when no pipe or child can be made (nothing was read then); DeadlineExceeded, naming
// what the child was waiting in, when it had not finished by `deadline` (it is killed and reaped).
absl::StatusOr<ChildExit> RunIsolated(const std::function<bool(int fd)>& child,
                                      const std::function<void(std::string_view)>& on_bytes,
                                      absl::Time deadline = absl::InfiniteFuture());

// Writes all of `bytes` to fd (retrying short writes); false on an error.
bool WriteAll(int fd, std::string_view bytes);

// "LMDB aborted reading it (signal 6)" or "the reading process exited with 3".
std::string DescribeChildExit(const ChildExit& exit);

}  // namespace fremen::storage
