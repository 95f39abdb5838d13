#include "storage/isolated_child.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fstream>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"

namespace fremen::storage {

namespace {

// In the child: every descriptor but stdin/out/err and `keep` is closed, so that it holds no other
// isolated child's pipe (a pipe's reader sees its end only when every copy of the write end is
// closed) and none of the parent's files.
void CloseAllBut(int keep) {
  if (keep > 3) close_range(3, static_cast<unsigned>(keep - 1), 0);
  close_range(static_cast<unsigned>(keep + 1), std::numeric_limits<unsigned>::max(), 0);
}

// The kernel function the process sleeps in ("futex_wait_queue", "pipe_write"), or "?".
std::string WaitChannel(pid_t pid) {
  std::ifstream in(absl::StrCat("/proc/", pid, "/wchan"));
  std::string channel;
  std::getline(in, channel);
  return channel.empty() || channel == "0" ? "?" : channel;
}

ChildExit Reap(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  ChildExit exit;
  if (WIFSIGNALED(status)) {
    exit.signal = WTERMSIG(status);
  } else {
    exit.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  return exit;
}

// poll()'s timeout until `deadline`: -1 for none, 0 when it has passed, else whole milliseconds
// rounded up.
int PollTimeout(absl::Time deadline) {
  if (deadline == absl::InfiniteFuture()) return -1;
  const absl::Duration left = deadline - absl::Now();
  if (left <= absl::ZeroDuration()) return 0;
  return static_cast<int>(std::min<int64_t>(absl::ToInt64Milliseconds(absl::Ceil(left, absl::Milliseconds(1))),
                                            std::numeric_limits<int>::max()));
}

}  // namespace

bool WriteAll(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<size_t>(n));
  }
  return true;
}

absl::StatusOr<ChildExit> RunIsolated(const std::function<bool(int fd)>& child,
                                      const std::function<void(std::string_view)>& on_bytes, absl::Time deadline) {
  if (PollTimeout(deadline) == 0) {
    return absl::DeadlineExceededError("the deadline had passed before the reading process was started");
  }
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) return absl::UnavailableError(absl::StrCat("pipe: ", std::strerror(errno)));
  const pid_t pid = fork();
  if (pid < 0) {
    const int error = errno;
    close(fds[0]);
    close(fds[1]);
    return absl::UnavailableError(absl::StrCat("fork: ", std::strerror(error)));
  }
  if (pid == 0) {
    // Debian's libabsl is built with its debug checks: every absl::Mutex lock consults a global
    // lock graph under a spin lock, which another thread of the parent may have held at the fork —
    // held for ever in this copy. Skipping the deadlock detection skips that lock (LmdbEnv's reads
    // take an absl::Mutex).
    absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);
    CloseAllBut(fds[1]);
    signal(SIGPIPE, SIG_IGN);
    _exit(child(fds[1]) ? 0 : 3);
  }
  close(fds[1]);
  char buffer[1 << 16];
  for (;;) {
    // Strict: past the deadline the child is killed even while it is still writing.
    const int timeout = PollTimeout(deadline);
    pollfd readable{fds[0], POLLIN, 0};
    const int ready = timeout == 0 ? 0 : poll(&readable, 1, timeout);
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {
      const std::string channel = WaitChannel(pid);
      kill(pid, SIGKILL);
      close(fds[0]);
      (void)Reap(pid);
      return absl::DeadlineExceededError(
          absl::StrCat("the reading process had not finished by the deadline (it was waiting in ", channel,
                       ") and was killed"));
    }
    if (ready < 0) break;
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    on_bytes(std::string_view(buffer, static_cast<size_t>(n)));
  }
  close(fds[0]);
  return Reap(pid);
}

std::string DescribeChildExit(const ChildExit& exit) {
  if (exit.signal != 0) return absl::StrCat("LMDB aborted reading it (signal ", exit.signal, ")");
  return absl::StrCat("the reading process exited with ", exit.exit_code);
}

}  // namespace fremen::storage
