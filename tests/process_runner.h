// Runs a program to completion for a test, without a shell: the arguments go to execve as they
// are (no quoting), stdout and stderr come back apart (errors are looked for where the program
// writes them), and a program that hangs is killed after a timeout, so that the test fails instead
// of hanging ctest.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace fremen::testing {

struct RunOptions {
  // Written to the program's stdin, which is then closed (an empty text: stdin at end of file).
  std::string stdin_text;
  // NAME=VALUE added to the test's own environment, replacing a variable of the same name.
  std::vector<std::pair<std::string, std::string>> env;
  // After this the program (and the process group it leads) is killed with SIGKILL.
  std::chrono::milliseconds timeout = std::chrono::minutes(2);
  // When set, stderr is also appended to this file as it arrives: for a test that watches what a
  // program still running says (RunProgram on another thread).
  std::string stderr_copy_path;
};

struct RunResult {
  int exit_code = -1;      // -1: did not exit normally (see signal, timed_out)
  int signal = 0;          // the signal that ended the program, 0 when it exited
  bool timed_out = false;  // killed because it outlived RunOptions::timeout
  std::string out;         // stdout
  std::string err;         // stderr
};

// Runs `binary` (a path, not looked up in PATH) with `args` (argv[1...]) and waits for it to end.
// A program that cannot be started exits with 127 and says why on err.
RunResult RunProgram(const std::string& binary, const std::vector<std::string>& args,
                     const RunOptions& options = {});

// "exit code 3", "killed by signal 9", "timed out": for test failure messages.
std::string Describe(const RunResult& result);

// Starts `binary` (a path) with `args` in the background — a daemon the test talks to — with stdout
// and stderr to `output_path` (truncated). The child is killed (SIGKILL) when the test process
// dies, even by a crash. Its pid (the caller waits for it), or -1 when fork fails; a program that
// cannot be started exits with 127.
pid_t SpawnBackground(const std::string& binary, const std::vector<std::string>& args,
                      const std::string& output_path);

// The whole text of a file ("" when it cannot be read): a log a test inspects.
std::string ReadTextFile(const std::string& path);

}  // namespace fremen::testing
