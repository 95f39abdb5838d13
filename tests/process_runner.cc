#include "tests/process_runner.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <sstream>

#include "absl/strings/str_cat.h"

extern char** environ;

namespace fremen::testing {

namespace {

using Clock = std::chrono::steady_clock;

// The test's environment with `extra` set on top, as NAME=VALUE strings.
std::vector<std::string> Environment(const std::vector<std::pair<std::string, std::string>>& extra) {
  std::map<std::string, std::string> variables;
  for (char** entry = environ; *entry != nullptr; ++entry) {
    const std::string text = *entry;
    const size_t equals = text.find('=');
    if (equals != std::string::npos) variables[text.substr(0, equals)] = text.substr(equals + 1);
  }
  for (const auto& [name, value] : extra) variables[name] = value;
  std::vector<std::string> env;
  for (const auto& [name, value] : variables) env.push_back(absl::StrCat(name, "=", value));
  return env;
}

std::vector<char*> Pointers(std::vector<std::string>& strings) {
  std::vector<char*> pointers;
  for (std::string& s : strings) pointers.push_back(s.data());
  pointers.push_back(nullptr);
  return pointers;
}

void CloseIfOpen(int& fd) {
  if (fd >= 0) close(fd);
  fd = -1;
}

}  // namespace

RunResult RunProgram(const std::string& binary, const std::vector<std::string>& args, const RunOptions& options) {
  RunResult result;
  // Writing to a program that exited before reading all of its stdin must fail with EPIPE, not
  // kill the test.
  signal(SIGPIPE, SIG_IGN);

  std::vector<std::string> argv_strings = {binary};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<std::string> env_strings = Environment(options.env);
  // Built before fork: the child only calls async-signal-safe functions.
  std::vector<char*> argv = Pointers(argv_strings), envp = Pointers(env_strings);
  const std::string exec_failed = absl::StrCat("cannot execute ", binary, ": ");

  int in_pipe[2], out_pipe[2], err_pipe[2];
  if (pipe2(in_pipe, O_CLOEXEC) != 0 || pipe2(out_pipe, O_CLOEXEC) != 0 || pipe2(err_pipe, O_CLOEXEC) != 0) {
    result.exit_code = 127;
    result.err = absl::StrCat("pipe: ", strerror(errno));
    return result;
  }
  const pid_t pid = fork();
  if (pid == 0) {
    // Its own process group, so that a timeout kills what it started too (a shell's children);
    // and it dies with the test.
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    signal(SIGPIPE, SIG_DFL);
    dup2(in_pipe[0], STDIN_FILENO);
    dup2(out_pipe[1], STDOUT_FILENO);
    dup2(err_pipe[1], STDERR_FILENO);
    execve(binary.c_str(), argv.data(), envp.data());
    const char* reason = strerror(errno);
    (void)!write(STDERR_FILENO, exec_failed.data(), exec_failed.size());
    (void)!write(STDERR_FILENO, reason, strlen(reason));
    _exit(127);
  }
  close(in_pipe[0]);
  close(out_pipe[1]);
  close(err_pipe[1]);
  int in_fd = in_pipe[1], out_fd = out_pipe[0], err_fd = err_pipe[0];
  if (pid < 0) {
    CloseIfOpen(in_fd);
    CloseIfOpen(out_fd);
    CloseIfOpen(err_fd);
    result.exit_code = 127;
    result.err = absl::StrCat("fork: ", strerror(errno));
    return result;
  }
  fcntl(in_fd, F_SETFL, O_NONBLOCK);
  size_t written = 0;
  if (options.stdin_text.empty()) CloseIfOpen(in_fd);

  // stdin, stdout and stderr served together, so that a program blocked writing one stream while
  // the test waits on another cannot deadlock.
  const auto deadline = Clock::now() + options.timeout;
  const int err_copy =
      options.stderr_copy_path.empty() ? -1 : open(options.stderr_copy_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  char buffer[65536];
  while (out_fd >= 0 || err_fd >= 0 || in_fd >= 0) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      result.timed_out = true;
      break;
    }
    pollfd fds[3] = {{out_fd, POLLIN, 0}, {err_fd, POLLIN, 0}, {in_fd, POLLOUT, 0}};
    const int ready = poll(fds, 3, static_cast<int>(std::min<long long>(left, 1000)));
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || fds[i].revents == 0) continue;
      const ssize_t n = read(fds[i].fd, buffer, sizeof buffer);
      if (n > 0) {
        (i == 0 ? result.out : result.err).append(buffer, n);
        if (i == 1 && err_copy >= 0) (void)!write(err_copy, buffer, n);
      } else if (n == 0 || errno != EINTR) {
        CloseIfOpen(i == 0 ? out_fd : err_fd);
      }
    }
    if (in_fd >= 0 && fds[2].revents != 0) {
      const ssize_t n = write(in_fd, options.stdin_text.data() + written, options.stdin_text.size() - written);
      if (n > 0) written += n;
      if ((n < 0 && errno != EAGAIN && errno != EINTR) || written == options.stdin_text.size()) CloseIfOpen(in_fd);
    }
  }
  if (result.timed_out) kill(-pid, SIGKILL);
  if (err_copy >= 0) close(err_copy);
  CloseIfOpen(in_fd);
  CloseIfOpen(out_fd);
  CloseIfOpen(err_fd);

  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.signal = WTERMSIG(status);
  }
  return result;
}

std::string Describe(const RunResult& result) {
  if (result.timed_out) return "timed out";
  if (result.signal != 0) return absl::StrCat("killed by signal ", result.signal);
  return absl::StrCat("exit code ", result.exit_code);
}

pid_t SpawnBackground(const std::string& binary, const std::vector<std::string>& args,
                      const std::string& output_path) {
  std::vector<std::string> argv_strings = {binary};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv = Pointers(argv_strings);
  const pid_t pid = fork();
  if (pid == 0) {
    // A test that crashes must not leave its daemon running.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    const int out = open(output_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0) _exit(126);
    dup2(out, STDOUT_FILENO);
    dup2(out, STDERR_FILENO);
    close(out);
    execv(binary.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace fremen::testing
