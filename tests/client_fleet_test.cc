// The client library's fleet-wide views (client/lib/fleet_client.h) against three real fremend
// processes on loopback, each asked directly: the merged map list names every map with the daemon
// that holds it, a map on two daemons is reported on both, each daemon's status and their sum;
// after kill -9 of one daemon its address and UNAVAILABLE come back beside the others' answers.
// Every daemon wants tokens, and the fleet's one ConnectionOptions carries the token to each.
// fremenctl's --address A,B,C views, built on the same FleetClient, run as a subprocess.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/lib/client.h"
#include "client/lib/fleet_client.h"
#include "client/lib/placement.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Client;
using ::fremen::client::ConnectionOptions;
using ::fremen::client::FleetClient;
using ::fremen::client::FleetMap;
using ::fremen::client::FleetMaps;
using ::fremen::client::FleetStatus;
using ::fremen::client::Placement;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr int kDaemons = 3;
constexpr char kWriteToken[] = "fleet-writer";

class FleetClientTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < kDaemons; ++i) {
      auto process = FremendProcess::Start(dir_.Path(absl::StrCat("daemon-", i)),
                                           {"--tokens", absl::StrCat("read:fleet-reader write:", kWriteToken)});
      ASSERT_TRUE(process.ok()) << process.status();
      addresses_.push_back((*process)->address());
      daemons_.push_back(*std::move(process));
    }
  }

  // The options every client here uses: the write token, and few retries, so that a daemon that
  // was killed answers UNAVAILABLE soon rather than at the deadline.
  static ConnectionOptions Options(const std::string& token = kWriteToken) {
    ConnectionOptions options;
    options.token = token;
    options.retry.max_attempts = 2;
    return options;
  }

  Client ClientOf(int daemon) const {
    ConnectionOptions options = Options();
    options.address = addresses_[daemon];
    return *Client::Connect(options);
  }

  void CreateOn(int daemon, const std::string& name) const {
    auto created = ClientOf(daemon).CreateMap(GenericMapSpec(name));
    ASSERT_TRUE(created.ok()) << name << " on " << addresses_[daemon] << ": " << created.status();
  }

  static std::vector<std::string> Rows(const FleetMaps& fleet) {
    std::vector<std::string> rows;
    for (const FleetMap& m : fleet.maps) {
      rows.push_back(absl::StrCat(m.map.name(), "@", m.daemon, m.duplicate ? " duplicate" : ""));
    }
    return rows;
  }

  TempDir dir_;
  std::vector<std::string> addresses_;
  std::vector<std::unique_ptr<FremendProcess>> daemons_;
};

TEST_F(FleetClientTest, ListsEveryMapOfEveryDaemonWithTheDaemonThatHoldsIt) {
  CreateOn(0, "lab");
  CreateOn(0, "office");
  CreateOn(1, "garage");
  CreateOn(2, "atrium");
  CreateOn(2, "office");  // a second copy, as during a move: reported on both daemons
  // Items may themselves be comma-separated lists, as --address is.
  auto fleet = FleetClient::Connect({addresses_[0], absl::StrCat(addresses_[1], ",", addresses_[2])}, Options());
  ASSERT_TRUE(fleet.ok()) << fleet.status();
  ASSERT_EQ(fleet->members().size(), 3u);
  EXPECT_EQ(fleet->members()[1].address, addresses_[1]);

  const FleetMaps maps = fleet->ListAllMaps();
  EXPECT_THAT(Rows(maps), ElementsAre(absl::StrCat("atrium@", addresses_[2]), absl::StrCat("garage@", addresses_[1]),
                                      absl::StrCat("lab@", addresses_[0]),
                                      absl::StrCat("office@", addresses_[0], " duplicate"),
                                      absl::StrCat("office@", addresses_[2], " duplicate")));
  EXPECT_THAT(maps.duplicates, ElementsAre("office"));
  ASSERT_EQ(maps.daemons.size(), 3u);
  for (int i = 0; i < kDaemons; ++i) {
    EXPECT_EQ(maps.daemons[i].address, addresses_[i]);
    EXPECT_TRUE(maps.daemons[i].status.ok()) << maps.daemons[i].status;
  }
  EXPECT_TRUE(maps.Unreachable().empty());
  // The maps are the daemons' own messages, defaults filled in.
  EXPECT_EQ(maps.maps[0].map.kind(), v1::MAP_KIND_GENERIC);
}

TEST_F(FleetClientTest, ReportsEachDaemonsStatusAndTheirSum) {
  CreateOn(0, "a");
  CreateOn(0, "b");
  CreateOn(2, "c");
  auto fleet = FleetClient::Connect(addresses_, Options());
  ASSERT_TRUE(fleet.ok()) << fleet.status();
  const FleetStatus status = fleet->GetServerStatus();
  ASSERT_EQ(status.daemons.size(), 3u);
  const uint64_t expected_maps[kDaemons] = {2, 0, 1};
  for (int i = 0; i < kDaemons; ++i) {
    EXPECT_EQ(status.daemons[i].address, addresses_[i]);
    ASSERT_TRUE(status.daemons[i].status.ok()) << status.daemons[i].status;
    EXPECT_EQ(status.daemons[i].server.map_count(), expected_maps[i]) << addresses_[i];
    EXPECT_TRUE(status.daemons[i].server.tokens_required());
  }
  EXPECT_EQ(status.summary.daemons, 3u);
  EXPECT_EQ(status.summary.answered, 3u);
  EXPECT_EQ(status.summary.map_count, 3u);
  EXPECT_EQ(status.summary.failed_maps, 0u);
  EXPECT_GT(status.summary.min_data_dir_free_bytes, 0u);
  ASSERT_EQ(status.summary.versions.size(), 1u);
  EXPECT_EQ(status.summary.versions[0], status.daemons[0].server.version());
  EXPECT_TRUE(status.summary.recovering.empty());
}

TEST_F(FleetClientTest, ADaemonThatDoesNotAnswerIsReportedAndTheOthersStillAnswer) {
  CreateOn(0, "lab");
  CreateOn(1, "garage");
  CreateOn(2, "atrium");
  auto fleet = FleetClient::Connect(addresses_, Options());
  ASSERT_TRUE(fleet.ok()) << fleet.status();
  daemons_[1]->Kill();

  const FleetMaps maps = fleet->ListAllMaps();
  EXPECT_THAT(Rows(maps), ElementsAre(absl::StrCat("atrium@", addresses_[2]), absl::StrCat("lab@", addresses_[0])));
  ASSERT_EQ(maps.Unreachable().size(), 1u);
  EXPECT_EQ(maps.Unreachable()[0].address, addresses_[1]);
  EXPECT_EQ(maps.Unreachable()[0].status.code(), absl::StatusCode::kUnavailable) << maps.Unreachable()[0].status;
  EXPECT_TRUE(maps.daemons[0].status.ok());
  EXPECT_TRUE(maps.daemons[2].status.ok());

  const FleetStatus status = fleet->GetServerStatus();
  EXPECT_EQ(status.daemons[1].status.code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(status.summary.answered, 2u);
  EXPECT_EQ(status.summary.map_count, 2u);
}

TEST_F(FleetClientTest, TheTokenOfTheOptionsGoesToEveryDaemon) {
  CreateOn(1, "garage");
  auto reader = FleetClient::Connect(addresses_, Options("fleet-reader"));
  ASSERT_TRUE(reader.ok()) << reader.status();
  const FleetMaps maps = reader->ListAllMaps();
  EXPECT_TRUE(maps.Unreachable().empty());
  EXPECT_THAT(Rows(maps), ElementsAre(absl::StrCat("garage@", addresses_[1])));

  auto anonymous = FleetClient::Connect(addresses_, Options(""));
  ASSERT_TRUE(anonymous.ok()) << anonymous.status();
  const FleetMaps refused = anonymous->ListAllMaps();
  EXPECT_TRUE(refused.maps.empty());
  ASSERT_EQ(refused.Unreachable().size(), 3u);
  for (const auto& d : refused.Unreachable()) EXPECT_EQ(d.status.code(), absl::StatusCode::kUnauthenticated);
}

TEST_F(FleetClientTest, ClientForIsTheOwnerByThePlacementOfTheNamedDaemons) {
  auto fleet = FleetClient::Connect(addresses_, Options());
  ASSERT_TRUE(fleet.ok()) << fleet.status();
  const Placement placement = *Placement::Create(addresses_);
  std::vector<std::string> names;
  for (int i = 0; i < 12; ++i) names.push_back(absl::StrCat("building-", i));
  for (const std::string& name : names) {
    auto owner = fleet->ClientFor(name);
    ASSERT_TRUE(owner.ok()) << owner.status();
    EXPECT_EQ(owner->connection()->address(), placement.Owner(name));
    ASSERT_TRUE(owner->CreateMap(GenericMapSpec(name)).ok()) << name;
  }
  const FleetMaps maps = fleet->ListAllMaps();
  ASSERT_EQ(maps.maps.size(), names.size());
  for (const FleetMap& m : maps.maps) EXPECT_EQ(m.daemon, placement.Owner(m.map.name())) << m.map.name();
}

TEST_F(FleetClientTest, AllHostPortIsEveryAddressTheNameResolvesTo) {
  CreateOn(0, "lab");
  auto fleet = FleetClient::Connect({absl::StrCat("all:", addresses_[0])}, Options());
  ASSERT_TRUE(fleet.ok()) << fleet.status();
  ASSERT_EQ(fleet->members().size(), 1u);
  EXPECT_EQ(fleet->members()[0].address, addresses_[0]);
  EXPECT_THAT(Rows(fleet->ListAllMaps()), ElementsAre(absl::StrCat("lab@", addresses_[0])));
  // Placement hashes the proxy's server strings, which resolved IPs are not.
  EXPECT_EQ(fleet->ClientFor("lab").status().code(), absl::StatusCode::kFailedPrecondition);

  auto unresolved = FleetClient::Connect({"all:no-such-daemon.invalid:50051"}, Options());
  EXPECT_EQ(unresolved.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(unresolved.status().message(), HasSubstr("cannot resolve no-such-daemon.invalid"));
  EXPECT_EQ(FleetClient::Connect({}, Options()).status().code(), absl::StatusCode::kInvalidArgument);
  auto twice = FleetClient::Connect({addresses_[0], addresses_[0]}, Options());
  EXPECT_EQ(twice.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(twice.status().message(), HasSubstr("named twice"));
}

// fremenctl's fleet views are the library's: the same merge, duplicates marked, the daemon that
// does not answer reported and the command exiting 1 after listing the others.
TEST_F(FleetClientTest, FremenctlListsTheFleetThroughTheLibrary) {
  CreateOn(0, "office");
  CreateOn(2, "office");
  CreateOn(2, "atrium");
  daemons_[1]->Kill();
  const std::string fleet = absl::StrCat(addresses_[0], ",", addresses_[1], ",", addresses_[2]);
  const RunResult list =
      RunProgram(FREMENCTL_BINARY, {"maps", "list", "--address", fleet, "--token", kWriteToken, "--timeout", "10"});
  EXPECT_EQ(list.exit_code, 1) << list.out << list.err;
  std::vector<std::string> lines = absl::StrSplit(list.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 4u) << list.out;
  EXPECT_THAT(lines[1], ::testing::StartsWith("atrium"));
  EXPECT_THAT(lines[2], ::testing::AllOf(HasSubstr(addresses_[0]), HasSubstr("DUPLICATE")));
  EXPECT_THAT(lines[3], ::testing::AllOf(HasSubstr(addresses_[2]), HasSubstr("DUPLICATE")));
  EXPECT_THAT(list.err, HasSubstr(absl::StrCat("listing the maps of ", addresses_[1])));
  EXPECT_THAT(list.err, HasSubstr("1 maps are held by more than one daemon"));

  const RunResult status =
      RunProgram(FREMENCTL_BINARY, {"status", "--address", fleet, "--token", kWriteToken, "--timeout", "10"});
  EXPECT_EQ(status.exit_code, 1) << status.out << status.err;
  EXPECT_THAT(status.out, HasSubstr("== fleet: 2 of 3 daemons answered; 3 maps"));
}

// fremenctl asks every daemon at once, a thread each, on fresh connections. gRPC 1.51 now and then
// reports such a connection as failed while it is still being made (with a stale errno: "No such
// file or directory"), and then fails every call on that channel at once until it is connected
// again: the pause before a retry must connect it. When it only slept, about one run of a fleet
// command in 150-600 failed so (this test, 500 runs, then failed about half the time).
TEST_F(FleetClientTest, FremenctlReachesEveryLiveDaemonRunAfterRun) {
  const std::string fleet = absl::StrJoin(addresses_, ",");
  for (int run = 0; run < 500; ++run) {
    const RunResult list =
        RunProgram(FREMENCTL_BINARY, {"maps", "list", "--address", fleet, "--token", kWriteToken, "--timeout", "10"});
    ASSERT_EQ(list.exit_code, 0) << "run " << run << ": " << list.out << list.err;
  }
}

}  // namespace
}  // namespace fremen::testing
