// Clients of a daemon's HTTP port for the end-to-end tests (cpp-httplib's, a real HTTP client).
#pragma once

#include <httplib.h>

#include <string>

#include "absl/strings/numbers.h"
#include "gtest/gtest.h"

namespace fremen::testing {

struct HostPort {
  std::string host;
  int port = 0;
};

// "HOST:PORT" (as FremendProcess::http_address says it) → its host and port.
inline HostPort SplitHostPort(const std::string& address) {
  const size_t colon = address.rfind(':');
  HostPort split{address.substr(0, colon), 0};
  EXPECT_TRUE(colon != std::string::npos && absl::SimpleAtoi(address.substr(colon + 1), &split.port)) << address;
  return split;
}

// A plain-HTTP client of `address`.
inline httplib::Client HttpClientFor(const std::string& address) {
  const HostPort split = SplitHostPort(address);
  return httplib::Client(split.host, split.port);
}

}  // namespace fremen::testing
