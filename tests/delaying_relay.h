// A TCP relay on a loopback port that holds each new connection for a while before it connects it
// to its upstream and copies bytes both ways: fault injection for a slow first handshake (a loaded
// daemon, a Wi-Fi link with a long round trip). It counts the connections it accepted, so a test
// can tell one patient connection attempt from several abandoned ones.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "base/mutex.h"

namespace fremen::testing {

class DelayingRelay {
 public:
  // Listens on a free loopback port; each accepted connection waits `delay`, then is joined to
  // `upstream` ("127.0.0.1:PORT").
  static absl::StatusOr<std::unique_ptr<DelayingRelay>> Start(const std::string& upstream, absl::Duration delay);
  ~DelayingRelay();

  // "127.0.0.1:PORT", where clients connect.
  const std::string& address() const { return address_; }
  int accepted() const { return accepted_; }

 private:
  DelayingRelay(int listener, std::string address, std::string upstream, absl::Duration delay);
  void AcceptLoop();
  void Relay(int client);

  const int listener_;
  const std::string address_, upstream_;
  const absl::Duration delay_;
  std::atomic<bool> stopping_{false};
  std::atomic<int> accepted_{0};
  base::Mutex mutex_;
  std::vector<int> sockets_ ABSL_GUARDED_BY(mutex_);
  std::vector<std::thread> relays_ ABSL_GUARDED_BY(mutex_);
  std::thread acceptor_;
};

}  // namespace fremen::testing
