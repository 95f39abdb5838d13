#include "tests/free_port.h"

#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <set>
#include <string>

#include "absl/strings/numbers.h"
#include "gtest/gtest.h"

namespace fremen::testing {
namespace {

int PortOf(const std::string& address) {
  int port = 0;
  EXPECT_TRUE(absl::SimpleAtoi(address.substr(address.rfind(':') + 1), &port)) << address;
  return port;
}

TEST(FreeLoopbackAddressTest, GivesEachPortOnceAndBelowTheEphemeralRange) {
  std::ifstream range("/proc/sys/net/ipv4/ip_local_port_range");
  int ephemeral_floor = 32768;
  range >> ephemeral_floor;
  std::set<int> ports;
  for (int i = 0; i < 200; ++i) {
    const std::string address = FreeLoopbackAddress();
    ASSERT_EQ(address.rfind("127.0.0.1:", 0), 0u) << address;
    const int port = PortOf(address);
    EXPECT_LT(port, ephemeral_floor);
    EXPECT_TRUE(ports.insert(port).second) << "port " << port << " given twice";
  }
}

// Another test process (ctest -j) never gets a port this one holds: the child takes 500 ports and
// exits 1 if any is among the parent's 300. Without the locks, some ~12 of the child's would be
// (500 × 300 over the ~12,700 ports of the range): the test would fail but for a chance of 1e-5.
TEST(FreeLoopbackAddressTest, AnotherProcessIsNotGivenAPortThisOneHolds) {
  std::set<int> mine;
  for (int i = 0; i < 300; ++i) mine.insert(PortOf(FreeLoopbackAddress()));
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    for (int i = 0; i < 500; ++i) {
      if (mine.count(PortOf(FreeLoopbackAddress())) > 0) _exit(1);
    }
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the child was given a port the parent holds";
}

}  // namespace
}  // namespace fremen::testing
