#include "tests/delaying_relay.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"

namespace fremen::testing {

namespace {

absl::StatusOr<sockaddr_in> LoopbackAddressOf(const std::string& address) {
  const size_t colon = address.rfind(':');
  int port = 0;
  if (colon == std::string::npos || !absl::SimpleAtoi(address.substr(colon + 1), &port)) {
    return absl::InvalidArgumentError(absl::StrCat("upstream ", address, ": not HOST:PORT"));
  }
  sockaddr_in in{};
  in.sin_family = AF_INET;
  in.sin_port = htons(static_cast<uint16_t>(port));
  if (inet_pton(AF_INET, address.substr(0, colon).c_str(), &in.sin_addr) != 1) {
    return absl::InvalidArgumentError(absl::StrCat("upstream ", address, ": not an IPv4 address"));
  }
  return in;
}

// Copies `from` to `to` until `from` ends, then ends `to`'s sending side. MSG_NOSIGNAL: a peer
// that has closed its end (the client at the end of a test) is a failed send, not a SIGPIPE that
// kills the test's process.
void Copy(int from, int to) {
  char buffer[16384];
  for (;;) {
    const ssize_t got = read(from, buffer, sizeof buffer);
    if (got <= 0) break;
    for (ssize_t sent = 0; sent < got;) {
      const ssize_t wrote = send(to, buffer + sent, static_cast<size_t>(got - sent), MSG_NOSIGNAL);
      if (wrote <= 0) {
        shutdown(to, SHUT_WR);
        return;
      }
      sent += wrote;
    }
  }
  shutdown(to, SHUT_WR);
}

}  // namespace

absl::StatusOr<std::unique_ptr<DelayingRelay>> DelayingRelay::Start(const std::string& upstream,
                                                                    absl::Duration delay) {
  if (absl::StatusOr<sockaddr_in> valid = LoopbackAddressOf(upstream); !valid.ok()) return valid.status();
  const int listener = socket(AF_INET, SOCK_STREAM, 0);
  if (listener < 0) return absl::InternalError(absl::StrCat("socket: ", std::strerror(errno)));
  sockaddr_in in{};
  in.sin_family = AF_INET;
  in.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof in;
  if (bind(listener, reinterpret_cast<sockaddr*>(&in), sizeof in) != 0 || listen(listener, 16) != 0 ||
      getsockname(listener, reinterpret_cast<sockaddr*>(&in), &length) != 0) {
    const std::string error = std::strerror(errno);
    close(listener);
    return absl::InternalError(absl::StrCat("relay listener: ", error));
  }
  return std::unique_ptr<DelayingRelay>(
      new DelayingRelay(listener, absl::StrCat("127.0.0.1:", ntohs(in.sin_port)), upstream, delay));
}

DelayingRelay::DelayingRelay(int listener, std::string address, std::string upstream, absl::Duration delay)
    : listener_(listener), address_(std::move(address)), upstream_(std::move(upstream)), delay_(delay) {
  acceptor_ = std::thread([this] { AcceptLoop(); });
}

DelayingRelay::~DelayingRelay() {
  stopping_ = true;
  // Wakes accept() and every read() blocked on a relayed connection.
  shutdown(listener_, SHUT_RDWR);
  acceptor_.join();
  std::vector<std::thread> relays;
  {
    base::MutexLock lock(&mutex_);
    for (int socket : sockets_) shutdown(socket, SHUT_RDWR);
    relays.swap(relays_);
  }
  for (std::thread& relay : relays) relay.join();
  base::MutexLock lock(&mutex_);
  for (int socket : sockets_) close(socket);
  close(listener_);
}

void DelayingRelay::AcceptLoop() {
  while (!stopping_) {
    const int client = accept(listener_, nullptr, nullptr);
    if (client < 0) {
      if (errno == EINTR) continue;
      return;
    }
    ++accepted_;
    base::MutexLock lock(&mutex_);
    sockets_.push_back(client);
    relays_.emplace_back([this, client] { Relay(client); });
  }
}

void DelayingRelay::Relay(int client) {
  for (absl::Time until = absl::Now() + delay_; absl::Now() < until && !stopping_;) {
    absl::SleepFor(absl::Milliseconds(10));
  }
  const int upstream = socket(AF_INET, SOCK_STREAM, 0);
  const sockaddr_in to = *LoopbackAddressOf(upstream_);
  {
    base::MutexLock lock(&mutex_);
    sockets_.push_back(upstream);
  }
  if (!stopping_ && connect(upstream, reinterpret_cast<const sockaddr*>(&to), sizeof to) == 0) {
    std::thread back([client, upstream] { Copy(upstream, client); });
    Copy(client, upstream);
    back.join();
  }
  // Closed by the destructor, after every relay has ended: a number closed here could be reused by
  // another socket of the process while the destructor still names it in a shutdown.
  shutdown(client, SHUT_RDWR);
  shutdown(upstream, SHUT_RDWR);
}

}  // namespace fremen::testing
