#include "storage/isolated_child.h"

#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <atomic>
#include <string>
#include <thread>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"

namespace fremen::storage {
namespace {

using ::testing::HasSubstr;

// Runs `child` with no deadline and returns what it wrote; the exit in *exit.
std::string Collect(const std::function<bool(int)>& child, ChildExit* exit,
                    absl::Time deadline = absl::InfiniteFuture()) {
  std::string bytes;
  auto ended = RunIsolated(child, [&](std::string_view chunk) { bytes.append(chunk); }, deadline);
  EXPECT_TRUE(ended.ok()) << ended.status();
  if (ended.ok()) *exit = *ended;
  return bytes;
}

TEST(IsolatedChildTest, TheParentGetsEveryByteAndTheExit) {
  ChildExit exit;
  const std::string big(1 << 20, 'x');  // more than a pipe holds: read while the child writes
  EXPECT_EQ(Collect([&](int fd) { return WriteAll(fd, "head:") && WriteAll(fd, big); }, &exit), "head:" + big);
  EXPECT_TRUE(exit.ok());
}

TEST(IsolatedChildTest, AFalseReturnAndAnAbortAreTold) {
  ChildExit exit;
  Collect([](int) { return false; }, &exit);
  EXPECT_EQ(exit.exit_code, 3);
  EXPECT_EQ(exit.signal, 0);
  EXPECT_EQ(DescribeChildExit(exit), "the reading process exited with 3");
  Collect([](int) -> bool { std::abort(); }, &exit);
  EXPECT_EQ(exit.signal, SIGABRT);
  EXPECT_EQ(DescribeChildExit(exit), "LMDB aborted reading it (signal 6)");
}

TEST(IsolatedChildTest, TheChildHoldsNoDescriptorOfTheParentButItsPipe) {
  int other[2];
  ASSERT_EQ(pipe(other), 0);  // another thread's pipe, say, without O_CLOEXEC
  ChildExit exit;
  const std::string seen = Collect(
      [&](int fd) {
        const bool read_end = fcntl(other[0], F_GETFD) != -1, write_end = fcntl(other[1], F_GETFD) != -1;
        const bool own = fcntl(fd, F_GETFD) != -1;
        return WriteAll(fd, absl::StrCat(read_end, write_end, own));
      },
      &exit);
  EXPECT_EQ(seen, "001");
  close(other[0]);
  close(other[1]);
}

TEST(IsolatedChildTest, AChildStillRunningAtTheDeadlineIsKilledAndReaped) {
  std::string bytes;
  // The child tells its pid, then blocks for good on a pipe nobody writes to.
  auto ended = RunIsolated(
      [](int fd) {
        int never[2];
        if (pipe(never) != 0 || !WriteAll(fd, absl::StrCat(getpid(), "\n"))) return false;
        char c;
        return read(never[0], &c, 1) == 1;
      },
      [&](std::string_view chunk) { bytes.append(chunk); }, absl::Now() + absl::Milliseconds(200));
  ASSERT_TRUE(absl::IsDeadlineExceeded(ended.status())) << ended.status();
  EXPECT_THAT(ended.status().message(), HasSubstr("had not finished by the deadline (it was waiting in "));
  pid_t pid = 0;
  ASSERT_TRUE(absl::SimpleAtoi(bytes.substr(0, bytes.find('\n')), &pid)) << bytes;
  EXPECT_EQ(kill(pid, 0), -1);  // reaped: the pid names no process, not even a zombie
  EXPECT_EQ(errno, ESRCH);
}

TEST(IsolatedChildTest, APassedDeadlineStartsNoChild) {
  bool called = false;
  auto ended = RunIsolated([](int fd) { return WriteAll(fd, "x"); }, [&](std::string_view) { called = true; },
                           absl::InfinitePast());
  EXPECT_TRUE(absl::IsDeadlineExceeded(ended.status())) << ended.status();
  EXPECT_THAT(ended.status().message(), HasSubstr("before the reading process was started"));
  EXPECT_FALSE(called);
}

}  // namespace
}  // namespace fremen::storage

namespace fremen::storage {
namespace {

// A child that takes an absl::Mutex (LmdbEnv's reads do) while another thread of the parent locks
// and unlocks absl::Mutexes without pause: absl's debug-mode deadlock detection guards its global
// lock graph with a spin lock that such a thread holds now and then, and a child forked at that
// moment inherited it held and waited for it forever (a verification that never ended).
TEST(IsolatedChildTest, AChildTakesAnAbslMutexWhileTheParentsThreadsAreLocking) {
  std::atomic<bool> stop{false};
  std::thread locker([&] {
    absl::Mutex a, b;
    while (!stop) {
      absl::MutexLock la(&a);
      absl::MutexLock lb(&b);
    }
  });
  int hung = 0;
  for (int i = 0; i < 300 && hung == 0; ++i) {
    auto ended = RunIsolated(
        [](int) {
          absl::Mutex fresh;
          absl::ReaderMutexLock lock(&fresh);
          return true;
        },
        [](std::string_view) {}, absl::Now() + absl::Seconds(10));
    if (!ended.ok() || !ended->ok()) ++hung;
  }
  stop = true;
  locker.join();
  EXPECT_EQ(hung, 0) << "a child waited for a lock it inherited held";
}

}  // namespace
}  // namespace fremen::storage
