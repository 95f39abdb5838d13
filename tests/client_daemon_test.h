// A fixture for end-to-end tests that talk to the real fremend through the C++ client library
// (client/lib): the daemon of DaemonTest, a Client connected to it, and the update job run to its
// end. Header-only: its users link fremend_fixture and fremen_client.
#pragma once

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "client/lib/client.h"
#include "tests/fremend_fixture.h"

namespace fremen::testing {

class ClientDaemonTest : public DaemonTest {
 protected:
  // Connects client_ to the running daemon (a fatal failure when it cannot).
  void ConnectClient() {
    client::ConnectionOptions options;
    options.address = daemon_->address();
    auto connected = client::Client::Connect(options);
    ASSERT_TRUE(connected.ok()) << connected.status();
    client_.emplace(*std::move(connected));
  }

  // Runs the update job on `map` and waits until it has ended without an error.
  void UpdateAndWait(const std::string& map) {
    auto op = client_->RunUpdate(map);
    ASSERT_TRUE(op.ok()) << op.status();
    client::WaitOptions wait;
    wait.poll_interval = absl::Milliseconds(50);
    auto done = client_->WaitOperation(map, op->name(), wait);
    ASSERT_TRUE(done.ok()) << done.status();
    ASSERT_EQ(done->error().code(), 0) << done->error().message();
  }

  std::optional<client::Client> client_;
};

}  // namespace fremen::testing
