#include "tests/free_port.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <random>

#include "absl/strings/str_cat.h"

namespace fremen::testing {

namespace {

// The reserved range's floor; its ceiling is the ephemeral range's floor (32768 by default).
constexpr int kLowestPort = 20000;
constexpr int kAttempts = 2000;

int EphemeralFloor() {
  std::ifstream range("/proc/sys/net/ipv4/ip_local_port_range");
  int low = 0;
  return range >> low ? low : 32768;
}

bool CanBind(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  const int yes = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<uint16_t>(port));
  const bool bound = bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  close(fd);
  return bound;
}

// The lock file of `port`, opened and locked for the rest of the process, or false when another
// process (or an earlier call of this one: flock locks belong to the open file) holds it.
bool Reserve(const std::string& dir, int port) {
  const int fd = open(absl::StrCat(dir, "/", port).c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) return false;
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    close(fd);
    return false;
  }
  return true;  // the descriptor stays open: the lock lasts until the process exits
}

}  // namespace

std::string FreeLoopbackAddress() {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  const std::string dir = "/tmp/fremen-test-ports";
  mkdir(dir.c_str(), 01777);
  chmod(dir.c_str(), 01777);  // every user's tests share it (mkdir's mode is masked)
  const int ceiling = EphemeralFloor();
  if (ceiling - kLowestPort < 1000) {
    std::fprintf(stderr, "FreeLoopbackAddress: the ephemeral ports start at %d, too low to keep test ports apart\n",
                 ceiling);
    std::abort();
  }
  static std::mt19937 random(std::random_device{}());
  std::uniform_int_distribution<int> pick(kLowestPort, ceiling - 1);
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    const int port = pick(random);
    if (Reserve(dir, port) && CanBind(port)) return absl::StrCat("127.0.0.1:", port);
    // A port in use by something else stays reserved (its lock file open): it is not tried again.
  }
  std::fprintf(stderr, "FreeLoopbackAddress: no free port in [%d, %d) after %d attempts\n", kLowestPort, ceiling,
               kAttempts);
  std::abort();
}

}  // namespace fremen::testing
