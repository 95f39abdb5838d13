// A fleet on loopback, all real processes (docs/fleet.md): three fremend daemons behind a real
// nginx configured by deploy/nginx/render.py. Maps created through the proxy land on the owners
// that client/lib/placement.h (and `fremenctl fleet placement`) predict, asked of each daemon
// directly; six writers ingest through the proxy and every acknowledged observation is at the
// owner, counts exact; HTTP requests reach the same owner as gRPC calls; after kill -9 of one
// daemon its maps answer UNAVAILABLE through the proxy while the others serve, and after its
// restart they are back with their data.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/lib/client.h"
#include "client/lib/placement.h"
#include "tests/fremend_fixture.h"
#include "tests/http_client.h"
#include "tests/map_specs.h"
#include "tests/nginx_proxy.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Client;
using ::fremen::client::ConnectionOptions;
using ::fremen::client::Placement;
using ::fremen::client::ScanBuilder;
using ::testing::HasSubstr;

constexpr int kDaemons = 3;
constexpr double kStart = 1.7e9;

struct Member {
  std::string grpc, http, data_dir;
  std::unique_ptr<FremendProcess> process;
};

std::string MapName(int i) { return absl::StrFormat("building-%02d", i); }

class FleetRoutingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (NginxBinary().empty()) GTEST_SKIP() << "nginx is not installed (scripts/install-deps.sh installs nginx-light)";
    std::vector<std::string> names;
    std::vector<ProxiedDaemon> proxied;
    for (int i = 0; i < kDaemons; ++i) {
      Member m{FreeLoopbackAddress(), FreeLoopbackAddress(), dir_.Path(absl::StrCat("daemon-", i)), nullptr};
      names.push_back(m.grpc);
      proxied.push_back({m.grpc, m.http});
      members_.push_back(std::move(m));
      StartMember(i);
      if (HasFatalFailure()) return;
    }
    placement_.emplace(*Placement::Create(names));
    std::filesystem::create_directories(dir_.Path("nginx"));
    auto proxy = NginxProxy::Start(dir_.Path("nginx"), proxied);
    ASSERT_TRUE(proxy.ok()) << proxy.status();
    proxy_ = *std::move(proxy);
    proxy_client_.emplace(ClientOf(proxy_->grpc_address()));
  }

  void StartMember(int i) {
    Member& m = members_[i];
    auto process = FremendProcess::Start(m.data_dir, {"--listen", m.grpc, "--http-listen", m.http});
    ASSERT_TRUE(process.ok()) << process.status();
    m.process = *std::move(process);
  }

  // A client that tries each call once: the test looks at what one call through the proxy answers.
  static Client ClientOf(const std::string& address, int attempts = 1) {
    ConnectionOptions options;
    options.address = address;
    options.retry.max_attempts = attempts;
    return *Client::Connect(options);
  }

  int MemberOf(const std::string& grpc_address) const {
    for (int i = 0; i < kDaemons; ++i) {
      if (members_[i].grpc == grpc_address) return i;
    }
    ADD_FAILURE() << "no daemon at " << grpc_address;
    return 0;
  }
  int OwnerOf(const std::string& map) const { return MemberOf(placement_->Owner(map)); }

  // Creates maps 0..count-1 through the proxy (every third a grid, the rest generic).
  void CreateMaps(int count) {
    for (int i = 0; i < count; ++i) {
      v1::Map spec = i % 3 == 0 ? GridMapSpec(MapName(i), 20, 10, 0.5) : GenericMapSpec(MapName(i));
      spec.set_shards(1);
      auto created = proxy_client_->CreateMap(spec);
      ASSERT_TRUE(created.ok()) << MapName(i) << ": " << created.status();
    }
  }

  // The names of the maps each daemon holds, asked of it directly.
  std::vector<std::set<std::string>> HeldMaps() const {
    std::vector<std::set<std::string>> held(kDaemons);
    for (int i = 0; i < kDaemons; ++i) {
      auto maps = ClientOf(members_[i].grpc, 4).ListAllMaps();
      EXPECT_TRUE(maps.ok()) << members_[i].grpc << ": " << maps.status();
      if (!maps.ok()) continue;
      for (const v1::Map& map : *maps) held[i].insert(map.name());
    }
    return held;
  }

  RunResult Fremenctl(const std::vector<std::string>& args) const { return RunProgram(FREMENCTL_BINARY, args); }

  std::string AllDaemons() const {
    std::vector<std::string> names;
    for (const Member& m : members_) names.push_back(m.grpc);
    return absl::StrJoin(names, ",");
  }

  TempDir dir_;
  std::vector<Member> members_;
  std::optional<Placement> placement_;
  std::unique_ptr<NginxProxy> proxy_;
  std::optional<Client> proxy_client_;
};

TEST_F(FleetRoutingTest, MapsCreatedThroughTheProxyLandOnTheirPredictedOwners) {
  constexpr int kMaps = 30;
  CreateMaps(kMaps);
  const std::vector<std::set<std::string>> held = HeldMaps();
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    const int owner = OwnerOf(map);
    for (int d = 0; d < kDaemons; ++d) {
      EXPECT_EQ(held[d].count(map), d == owner ? 1u : 0u)
          << map << " on " << members_[d].grpc << "; its predicted owner is " << members_[owner].grpc;
    }
  }
  // 30 names spread over three daemons: each holds some (a broken ring would pile them up).
  for (int d = 0; d < kDaemons; ++d) EXPECT_GE(held[d].size(), 3u) << members_[d].grpc;

  // fremenctl agrees, offline (--map) and against the fleet (every held map at its owner: exit 0).
  const RunResult one = Fremenctl({"fleet", "placement", "--daemons", AllDaemons(), "--map", MapName(7)});
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_THAT(one.out, HasSubstr(absl::StrCat(MapName(7), " ", placement_->Owner(MapName(7)), "\n")));
  const RunResult all = Fremenctl({"fleet", "placement", "--address", AllDaemons()});
  ASSERT_EQ(all.exit_code, 0) << all.out << all.err;
  EXPECT_THAT(all.out, ::testing::Not(HasSubstr("MISPLACED")));
  for (int i = 0; i < kMaps; ++i) {
    const std::string owner = placement_->Owner(MapName(i));
    EXPECT_THAT(all.out, HasSubstr(absl::StrCat(MapName(i), " ", owner, " ", owner, "\n")));
  }

  // The merged listing names each map's daemon; status reports each daemon.
  const RunResult list = Fremenctl({"maps", "list", "--address", AllDaemons()});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  std::vector<std::string> lines = absl::StrSplit(list.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), kMaps + 1u) << list.out;
  EXPECT_THAT(lines[0], HasSubstr("DAEMON"));
  for (int i = 0; i < kMaps; ++i) {
    std::vector<std::string> columns = absl::StrSplit(lines[i + 1], ' ', absl::SkipEmpty());
    ASSERT_GE(columns.size(), 2u) << lines[i + 1];
    EXPECT_EQ(columns[0], MapName(i));
    EXPECT_EQ(columns[1], placement_->Owner(MapName(i)));
  }
  // all:HOST:PORT, every address HOST resolves to (one here), is a fleet too.
  const RunResult every = Fremenctl({"maps", "list", "--address", absl::StrCat("all:", members_[0].grpc)});
  ASSERT_EQ(every.exit_code, 0) << every.err;
  EXPECT_THAT(every.out, HasSubstr("DAEMON"));
  EXPECT_EQ(std::count(every.out.begin(), every.out.end(), '\n'), static_cast<long>(held[0].size() + 1)) << every.out;
  const RunResult unresolved = Fremenctl({"status", "--address", "all:no-such-daemon.invalid:50051"});
  EXPECT_EQ(unresolved.exit_code, 1);
  EXPECT_THAT(unresolved.err, HasSubstr("cannot resolve no-such-daemon.invalid"));
  const RunResult status = Fremenctl({"status", "--address", AllDaemons()});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  for (int d = 0; d < kDaemons; ++d) {
    EXPECT_THAT(status.out, HasSubstr(absl::StrCat("== ", members_[d].grpc, "\n")));
    EXPECT_THAT(status.out, HasSubstr(absl::StrCat("maps: ", held[d].size(), ",")));
  }
}

TEST_F(FleetRoutingTest, SixWritersThroughTheProxyLeaveEveryAcknowledgedObservationAtTheOwner) {
  constexpr int kMaps = 12;
  constexpr int kWriters = 6;
  constexpr int kMapsPerWriter = 4;
  constexpr int kBatches = 40;
  constexpr int kStates = 5;
  CreateMaps(kMaps);
  // Writer w writes maps w, w+3, w+6, w+9 (mod 12): every map has two writers at once.
  auto map_of = [](int writer, int k) { return (writer + 3 * k) % kMaps; };
  std::vector<std::vector<uint64_t>> accepted(kWriters, std::vector<uint64_t>(kMapsPerWriter, 0));
  std::vector<absl::Status> results(kWriters);
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w) {
    writers.emplace_back([&, w] {
      // Retries on: a writer through a proxy rides out what it must (nothing should be needed here).
      Client client = ClientOf(proxy_->grpc_address(), 0);
      for (int k = 0; k < kMapsPerWriter; ++k) {
        client::IngestOptions options;
        options.writer_id = 100 + w;
        auto session = client.OpenIngest(MapName(map_of(w, k)), options);
        if (!session.ok()) {
          results[w] = session.status();
          return;
        }
        for (int b = 0; b < kBatches; ++b) {
          ScanBuilder scan(kStart + 60.0 * b + w);
          if (map_of(w, k) % 3 == 0) {
            for (int s = 0; s < kStates; ++s) scan.AddCell({static_cast<uint32_t>(s + w), 3, 0}, (b + s) % 2);
          } else {
            for (int s = 0; s < kStates; ++s) scan.AddNamedState(absl::StrCat("door-", w, "-", s), (b + s) % 2);
          }
          if (auto sent = (*session)->Send(*scan.Build()); !sent.ok()) {
            results[w] = sent.status();
            return;
          }
        }
        if (absl::Status closed = (*session)->Close(); !closed.ok()) {
          results[w] = closed;
          return;
        }
        accepted[w][k] = (*session)->totals().accepted;
      }
    });
  }
  for (std::thread& t : writers) t.join();
  std::map<int, uint64_t> acknowledged;
  for (int w = 0; w < kWriters; ++w) {
    ASSERT_TRUE(results[w].ok()) << "writer " << w << ": " << results[w];
    for (int k = 0; k < kMapsPerWriter; ++k) {
      EXPECT_EQ(accepted[w][k], static_cast<uint64_t>(kBatches * kStates)) << "writer " << w << " map " << k;
      acknowledged[map_of(w, k)] += accepted[w][k];
    }
  }
  ASSERT_EQ(acknowledged.size(), static_cast<size_t>(kMaps));
  for (const auto& [i, count] : acknowledged) {
    const std::string map = MapName(i);
    const int owner = OwnerOf(map);
    auto stats = ClientOf(members_[owner].grpc, 4).GetMapStats(map);
    ASSERT_TRUE(stats.ok()) << map << " at its owner " << members_[owner].grpc << ": " << stats.status();
    EXPECT_EQ(stats->observations(), count) << map;
    for (int d = 0; d < kDaemons; ++d) {
      if (d == owner) continue;
      EXPECT_EQ(ClientOf(members_[d].grpc, 4).GetMapStats(map).status().code(), absl::StatusCode::kNotFound)
          << map << " also on " << members_[d].grpc;
    }
  }

  // The nightly job over the fleet: every map of every daemon updated, each where it is.
  const RunResult update =
      Fremenctl({"update", "--all", "--wait", "--poll-interval", "0.05", "--address", AllDaemons()});
  ASSERT_EQ(update.exit_code, 0) << update.out << update.err;
  EXPECT_THAT(update.out, HasSubstr(absl::StrCat("update --all: ", kMaps, " maps on 3 daemons: ", kMaps,
                                                 " updated, 0 failed")));
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    EXPECT_THAT(update.out, HasSubstr(absl::StrCat("(update of ", map, " on ", placement_->Owner(map), ")")));
    auto stats = ClientOf(placement_->Owner(map), 4).GetMapStats(map);
    ASSERT_TRUE(stats.ok()) << stats.status();
    EXPECT_GT(stats->dynamic_states(), 0u) << map;
  }
}

TEST_F(FleetRoutingTest, HttpRequestsReachTheDaemonThatHoldsTheMap) {
  constexpr int kMaps = 9;
  CreateMaps(kMaps);
  httplib::Client http = HttpClientFor(proxy_->http_address());
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    // By header: the owner's /metrics has the map's series (other daemons' have not).
    auto metrics = http.Get("/metrics", {{"x-fremen-map", map}});
    ASSERT_TRUE(metrics) << httplib::to_string(metrics.error());
    EXPECT_EQ(metrics->status, 200);
    EXPECT_THAT(metrics->body, HasSubstr(absl::StrCat("map=\"", map, "\""))) << map;
    // By path (the JSON API's /v1/maps/{map}/...): the proxy's log names the upstream it chose.
    auto by_path = http.Get(absl::StrCat("/v1/maps/", map, "/stats"));
    ASSERT_TRUE(by_path) << httplib::to_string(by_path.error());
  }
  // Its creation and two HTTP requests per map.
  const std::string log = proxy_->AccessLog(3 * kMaps);
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    EXPECT_THAT(log, HasSubstr(absl::StrCat("\"GET /v1/maps/", map, "/stats HTTP/1.1\" ")));
    EXPECT_THAT(log, HasSubstr(absl::StrCat("map=\"", map, "\" upstream=", members_[OwnerOf(map)].http, " ")))
        << map;
  }
}

TEST_F(FleetRoutingTest, AKilledDaemonsMapsAreUnavailableThroughTheProxyUntilItIsBack) {
  constexpr int kMaps = 30;
  CreateMaps(kMaps);
  constexpr int kVictim = 1;
  std::vector<std::string> victims;
  for (int i = 0; i < kMaps; ++i) {
    if (OwnerOf(MapName(i)) == kVictim) victims.push_back(MapName(i));
    if (i % 3 == 0) continue;  // a generic map: one observation, to find it again after the restart
    auto session = proxy_client_->OpenIngest(MapName(i));
    ASSERT_TRUE(session.ok()) << session.status();
    ASSERT_TRUE((*session)->Send(*ScanBuilder(kStart).AddNamedState("door", 1).Build()).ok());
    ASSERT_TRUE((*session)->Close().ok());
  }
  ASSERT_FALSE(victims.empty());

  members_[kVictim].process->Kill();
  httplib::Client http = HttpClientFor(proxy_->http_address());
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    auto got = proxy_client_->GetMap(map);
    if (OwnerOf(map) == kVictim) {
      EXPECT_EQ(got.status().code(), absl::StatusCode::kUnavailable) << map << ": " << got.status();
      EXPECT_THAT(got.status().message(),
                  HasSubstr(absl::StrCat("the daemon that holds map ", map, " is unavailable")));
      auto metrics = http.Get("/metrics", {{"x-fremen-map", map}});
      ASSERT_TRUE(metrics);
      EXPECT_EQ(metrics->status, 503) << map;
    } else {
      EXPECT_TRUE(got.ok()) << map << ": " << got.status();
    }
  }
  // Calls that name no map go to a daemon that answers.
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(proxy_client_->GetServerStatus().ok());
  // The fleet views say which daemon is missing, and exit 1.
  const RunResult list = Fremenctl({"maps", "list", "--address", AllDaemons()});
  EXPECT_EQ(list.exit_code, 1);
  EXPECT_THAT(list.err, HasSubstr(members_[kVictim].grpc));

  StartMember(kVictim);
  ASSERT_FALSE(HasFatalFailure());
  for (const std::string& map : victims) {
    auto got = proxy_client_->GetMap(map);
    EXPECT_TRUE(got.ok()) << map << ": " << got.status();
    auto stats = proxy_client_->GetMapStats(map);
    ASSERT_TRUE(stats.ok()) << map << ": " << stats.status();
    const int index = std::stoi(map.substr(map.size() - 2));
    EXPECT_EQ(stats->observations(), index % 3 == 0 ? 0u : 1u) << map;
  }
}

// What fremenctl refuses before it talks to anyone (exit 2, the message says what to fix).
TEST(FleetCommandLineTest, RefusesAFleetWhereOneDaemonIsMeantAndBadPlacements) {
  const auto run = [](const std::vector<std::string>& args) { return RunProgram(FREMENCTL_BINARY, args); };
  RunResult r = run({"maps", "get", "lab", "--address", "127.0.0.1:1,127.0.0.1:2"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--address names 2 daemons; this command talks to one"));
  EXPECT_EQ(run({"maps", "get", "lab", "--address", "all:localhost:1"}).exit_code, 2);
  r = run({"fleet", "placement", "--address", "all:fremend:50051", "--map", "lab"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("name the daemons one by one"));
  r = run({"fleet", "placement", "--daemons", "a:1,b:2,a:1", "--map", "lab"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("\"a:1\" is listed twice"));
  r = run({"fleet", "placement", "--daemons", "a:1,b:2", "--http", "a:3", "--map", "lab"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--http names 1 addresses for 2 daemons"));
  r = run({"update"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--map M, or --all"));
  EXPECT_EQ(run({"update", "--all", "--map", "lab"}).exit_code, 2);
  // Offline placement with both addresses of the owner.
  r = run({"fleet", "placement", "--daemons", "a:1,b:1", "--http", "a:2,b:2", "--map", "lab"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Placement fleet = *Placement::Create({"a:1", "b:1"});
  EXPECT_THAT(r.out, HasSubstr(absl::StrCat("lab ", fleet.Owner("lab"), " ", fleet.Owner("lab").substr(0, 1), ":2\n")));
}

}  // namespace
}  // namespace fremen::testing
