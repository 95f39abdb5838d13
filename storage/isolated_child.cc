#include "storage/isolated_child.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include "absl/strings/str_cat.h"

namespace fremen::storage {

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
                                      const std::function<void(std::string_view)>& on_bytes) {
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
    close(fds[0]);
    signal(SIGPIPE, SIG_IGN);
    _exit(child(fds[1]) ? 0 : 3);
  }
  close(fds[1]);
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    on_bytes(std::string_view(buffer, static_cast<size_t>(n)));
  }
  close(fds[0]);
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

std::string DescribeChildExit(const ChildExit& exit) {
  if (exit.signal != 0) return absl::StrCat("LMDB aborted reading it (signal ", exit.signal, ")");
  return absl::StrCat("the reading process exited with ", exit.exit_code);
}

}  // namespace fremen::storage
