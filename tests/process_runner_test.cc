// RunProgram (tests/process_runner.h) on /bin/sh: the streams apart, stdin, the environment, exit
// codes and signals, a timeout, and outputs larger than a pipe's buffer on both streams at once.
#include "tests/process_runner.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <string>

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

RunResult Shell(const std::string& script, const RunOptions& options = {}) {
  return RunProgram("/bin/sh", {"-c", script}, options);
}

TEST(RunProgramTest, StdoutAndStderrApartWithTheExitCode) {
  const RunResult r = Shell("echo out; echo err >&2; exit 3");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.out, "out\n");
  EXPECT_EQ(r.err, "err\n");
  EXPECT_EQ(r.signal, 0);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(Describe(r), "exit code 3");
}

TEST(RunProgramTest, ArgumentsReachTheProgramUnquoted) {
  // No shell between the test and the program: spaces, quotes and $ are the argument's own.
  const RunResult r = RunProgram("/bin/sh", {"-c", "printf '%s|' \"$@\"", "sh", "a b", "'c'", "$HOME", ""});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "a b|'c'|$HOME||");
}

TEST(RunProgramTest, StdinIsPassedThrough) {
  RunOptions options;
  options.stdin_text = "line one\nline two\n";
  const RunResult r = Shell("cat; echo done", options);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, "line one\nline two\ndone\n");
}

TEST(RunProgramTest, WithoutStdinTextTheProgramReadsEndOfFile) {
  const RunResult r = Shell("cat; echo eof");
  EXPECT_EQ(r.out, "eof\n");
}

TEST(RunProgramTest, StdinTheProgramDoesNotReadIsNoError) {
  RunOptions options;
  options.stdin_text = std::string(4 << 20, 'x');
  const RunResult r = Shell("exit 0", options);
  EXPECT_EQ(r.exit_code, 0);
}

TEST(RunProgramTest, EnvironmentVariablesAreAddedAndReplaced) {
  RunOptions options;
  options.env = {{"FREMEN_RUNNER_TEST", "added value"}, {"HOME", "/replaced"}};
  const RunResult r = Shell("echo \"$FREMEN_RUNNER_TEST\"; echo \"$HOME\"; echo \"${PATH:+path kept}\"", options);
  EXPECT_EQ(r.out, "added value\n/replaced\npath kept\n");
}

TEST(RunProgramTest, ASignalIsReported) {
  const RunResult r = Shell("kill -TERM $$");
  EXPECT_EQ(r.exit_code, -1);
  EXPECT_EQ(r.signal, SIGTERM);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(Describe(r), "killed by signal 15");
}

TEST(RunProgramTest, AHungProgramIsKilledAtTheTimeout) {
  RunOptions options;
  options.timeout = std::chrono::seconds(1);
  // The shell's child (sleep) holds the pipes too: the whole process group must go.
  const RunResult r = Shell("echo started; sleep 60; echo never", options);
  EXPECT_TRUE(r.timed_out);
  EXPECT_EQ(r.exit_code, -1);
  EXPECT_EQ(r.signal, SIGKILL);
  EXPECT_EQ(r.out, "started\n");
  EXPECT_EQ(Describe(r), "timed out");
}

TEST(RunProgramTest, LargeOutputOnBothStreamsDoesNotDeadlock) {
  // 8 MiB on each stream, written in turns, far more than a pipe holds: a runner that read one
  // stream to its end before the other would wait forever.
  const RunResult r = Shell(
      "i=0; while [ $i -lt 8 ]; do head -c 1048576 /dev/zero | tr '\\0' o; head -c 1048576 /dev/zero | tr '\\0' e >&2;"
      " i=$((i+1)); done");
  EXPECT_EQ(r.exit_code, 0) << Describe(r);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.out, std::string(8 << 20, 'o'));
  EXPECT_EQ(r.err, std::string(8 << 20, 'e'));
}

TEST(RunProgramTest, AProgramThatCannotBeStartedSaysWhy) {
  const RunResult r = RunProgram("/no/such/program", {});
  EXPECT_EQ(r.exit_code, 127);
  EXPECT_THAT(r.err, HasSubstr("cannot execute /no/such/program"));
  EXPECT_EQ(r.out, "");
}

}  // namespace
}  // namespace fremen::testing
