// A fleet that grows while it is written to, all real processes on loopback (docs/fleet.md,
// "Moving a map"): three fremend daemons behind a real nginx (master process and worker, as in
// production, so that a reload starts a new worker), 30 maps created through the proxy, six
// writers ingesting through the proxy without pause and a reader querying every map. A fourth
// daemon starts and `fremenctl fleet rebalance` moves exactly the maps whose owner changed onto it,
// reconfiguring nginx (render.py, nginx -s reload) before the old copies are dropped. Afterwards
// each daemon, asked directly, holds exactly the maps it owns under the new list (the others
// untouched), every acknowledged observation is at its owner — counts exact: no batch lost or
// applied twice — and neither a writer nor the reader ever saw NOT_FOUND. A second run finds
// nothing to move. A rebalance stopped before the proxy is reconfigured leaves the old copies
// refusing writes and is finished by running it again.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "base/mutex.h"
#include "client/lib/client.h"
#include "client/lib/placement.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"
#include "tests/nginx_proxy.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Client;
using ::fremen::client::ConnectionOptions;
using ::fremen::client::IngestSession;
using ::fremen::client::Placement;
using ::fremen::client::ScanBuilder;
using ::testing::HasSubstr;

constexpr int kFirstDaemons = 3;
constexpr int kMaps = 30;
constexpr int kWriters = 6;
constexpr double kStart = 1.7e9;

std::string MapName(int i) { return absl::StrFormat("building-%02d", i); }
bool IsGrid(int map) { return map % 3 == 0; }

// attempts 0: retries until the call's deadline, as a robot's client does.
Client ClientOf(const std::string& address, int attempts) {
  ConnectionOptions options;
  options.address = address;
  options.retry.max_attempts = attempts;
  options.retry.max_backoff = absl::Milliseconds(500);
  return *Client::Connect(options);
}

struct Member {
  std::string grpc, http, data_dir;
  std::unique_ptr<FremendProcess> process;
};

class Traffic;

class FleetRebalanceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (NginxBinary().empty()) GTEST_SKIP() << "nginx is not installed (scripts/install-deps.sh installs nginx-light)";
    for (int i = 0; i < kFirstDaemons; ++i) {
      members_.push_back({FreeLoopbackAddress(), FreeLoopbackAddress(), dir_.Path(absl::StrCat("daemon-", i)), nullptr});
      StartMember(i);
      if (HasFatalFailure()) return;
    }
    std::filesystem::create_directories(dir_.Path("nginx"));
    auto proxy = NginxProxy::Start(dir_.Path("nginx"), Proxied(kFirstDaemons), /*master_process=*/true);
    ASSERT_TRUE(proxy.ok()) << proxy.status();
    proxy_ = *std::move(proxy);
    // The fourth daemon's addresses now, so that the placements before and after are known (and
    // not among the ports nginx holds: gRPC binds with SO_REUSEPORT and would share one); it
    // starts later.
    members_.push_back({FreeLoopbackAddress(), FreeLoopbackAddress(), dir_.Path("daemon-3"), nullptr});
    before_.emplace(*Placement::Create(Names(kFirstDaemons)));
    after_.emplace(*Placement::Create(Names(kFirstDaemons + 1)));
    const Client client = ClientOf(proxy_->grpc_address(), 4);
    for (int i = 0; i < kMaps; ++i) {
      v1::Map spec = IsGrid(i) ? GridMapSpec(MapName(i), 20, 10, 0.5) : GenericMapSpec(MapName(i));
      spec.set_shards(1);
      auto created = client.CreateMap(spec);
      ASSERT_TRUE(created.ok()) << MapName(i) << ": " << created.status();
    }
  }

  void StartMember(int i) {
    Member& m = members_[i];
    auto process = FremendProcess::Start(m.data_dir, {"--listen", m.grpc, "--http-listen", m.http});
    ASSERT_TRUE(process.ok()) << process.status();
    m.process = *std::move(process);
  }

  std::vector<std::string> Names(int daemons) const {
    std::vector<std::string> names;
    for (int i = 0; i < daemons; ++i) names.push_back(members_[i].grpc);
    return names;
  }
  std::vector<ProxiedDaemon> Proxied(int daemons) const {
    std::vector<ProxiedDaemon> proxied;
    for (int i = 0; i < daemons; ++i) proxied.push_back({members_[i].grpc, members_[i].http});
    return proxied;
  }

  // Each daemon's maps by name, asked of it directly.
  std::vector<std::map<std::string, v1::Map>> HeldMaps(int daemons) const {
    std::vector<std::map<std::string, v1::Map>> held(daemons);
    for (int d = 0; d < daemons; ++d) {
      auto maps = ClientOf(members_[d].grpc, 4).ListAllMaps();
      EXPECT_TRUE(maps.ok()) << members_[d].grpc << ": " << maps.status();
      if (!maps.ok()) continue;
      for (const v1::Map& map : *maps) held[d][map.name()] = map;
    }
    return held;
  }

  RunResult Fremenctl(const std::vector<std::string>& args) const { return RunProgram(FREMENCTL_BINARY, args); }

  // The maps whose owner changes when the fourth daemon joins.
  std::set<std::string> Moving() const {
    std::set<std::string> moving;
    for (int i = 0; i < kMaps; ++i) {
      if (before_->Owner(MapName(i)) != after_->Owner(MapName(i))) moving.insert(MapName(i));
    }
    return moving;
  }

  // The rebalance onto the fourth daemon, reconfiguring nginx, with `extra` arguments.
  std::vector<std::string> RebalanceArgs(const std::vector<std::string>& extra = {}) const {
    std::vector<std::string> args = {"fleet", "rebalance", "--daemons", absl::StrJoin(Names(kFirstDaemons + 1), ","),
                                     "--proxy-command", proxy_->ReloadCommand(Proxied(kFirstDaemons + 1)), "--proxy",
                                     proxy_->grpc_address()};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }
  // Starts the writers, waits for ten batches acknowledged on every map (their counts in
  // `progress`), then starts the fourth daemon.
  void StartTrafficThenTheFourthDaemon(Traffic& traffic, std::vector<uint64_t>& progress);
  // The member whose gRPC address is `address`.
  int MemberAt(const std::string& address) const {
    for (size_t d = 0; d < members_.size(); ++d) {
      if (members_[d].grpc == address) return static_cast<int>(d);
    }
    return -1;
  }

  TempDir dir_;
  std::vector<Member> members_;
  std::optional<Placement> before_, after_;
  std::unique_ptr<NginxProxy> proxy_;
};

// Six writers, each with one ingest session per map of its share (maps w, w+6, ...), sending a
// batch to each in turn until told to stop; and a reader asking every map's stats in turn.
class Traffic {
 public:
  explicit Traffic(const std::string& proxy) : proxy_(proxy) {}
  // A test that failed before Stop() still ends the threads (a joinable std::thread's destructor
  // would abort the whole test binary).
  ~Traffic() { JoinThreads(); }

  absl::Status Start() {
    for (int i = 0; i < kMaps; ++i) {
      client::IngestOptions options;
      options.writer_id = 1000 + i;
      options.max_unacknowledged = 16;
      options.collect_acks = false;
      auto session = writer_clients_[i % kWriters].OpenIngest(MapName(i), options);
      if (!session.ok()) return session.status();
      sessions_[i] = *std::move(session);
    }
    for (int w = 0; w < kWriters; ++w) writers_.emplace_back([this, w] { Write(w); });
    reader_ = std::thread([this] { Read(); });
    return absl::OkStatus();
  }

  // Batches acknowledged so far on map i.
  uint64_t Acknowledged(int i) const { return sessions_[i]->totals().acknowledged; }
  // Waits until every map has had `more` batches acknowledged beyond `since` (its counts).
  std::vector<uint64_t> AwaitProgress(const std::vector<uint64_t>& since, uint64_t more) const {
    std::vector<uint64_t> now(kMaps);
    for (int i = 0; i < kMaps; ++i) {
      while (Acknowledged(i) < since[i] + more && !failed_) absl::SleepFor(absl::Milliseconds(10));
      now[i] = Acknowledged(i);
    }
    return now;
  }

  // Stops the writers and the reader; every session closed (all its batches acknowledged).
  void Stop() {
    JoinThreads();
    for (int i = 0; i < kMaps; ++i) {
      if (absl::Status closed = sessions_[i]->Close(); !closed.ok()) Fail(absl::StrCat(MapName(i), ": ", closed.ToString()));
    }
  }

  std::vector<std::string> failures() const {
    base::MutexLock lock(&mutex_);
    return failures_;
  }
  const IngestSession& session(int i) const { return *sessions_[i]; }
  uint64_t reads() const { return reads_; }

 private:
  void JoinThreads() {
    stop_ = true;
    for (std::thread& t : writers_) {
      if (t.joinable()) t.join();
    }
    if (reader_.joinable()) reader_.join();
  }
  void Fail(const std::string& what) {
    failed_ = true;
    base::MutexLock lock(&mutex_);
    failures_.push_back(what);
  }

  void Write(int w) {
    for (int b = 0; !stop_; ++b) {
      for (int i = w; i < kMaps && !stop_; i += kWriters) {
        ScanBuilder scan(kStart + 60.0 * b);
        for (int s = 0; s < 5; ++s) {
          if (IsGrid(i)) {
            scan.AddCell({static_cast<uint32_t>(s), 3, 0}, (b + s) % 2);
          } else {
            scan.AddNamedState(absl::StrCat("door-", s), (b + s) % 2);
          }
        }
        if (auto sent = sessions_[i]->Send(*scan.Build()); !sent.ok()) {
          Fail(absl::StrCat("writer ", w, ", ", MapName(i), ": ", sent.status().ToString()));
          return;
        }
      }
    }
  }

  void Read() {
    const Client client = ClientOf(proxy_, 0);
    for (int i = 0; !stop_; i = (i + 1) % kMaps) {
      auto stats = client.GetMapStats(MapName(i));
      if (!stats.ok()) Fail(absl::StrCat("reader, ", MapName(i), ": ", stats.status().ToString()));
      ++reads_;
    }
  }

  const std::string proxy_;
  std::vector<Client> writer_clients_ = [this] {
    std::vector<Client> clients;
    for (int w = 0; w < kWriters; ++w) clients.push_back(ClientOf(proxy_, 0));
    return clients;
  }();
  std::unique_ptr<IngestSession> sessions_[kMaps];
  std::vector<std::thread> writers_;
  std::thread reader_;
  std::atomic<bool> stop_{false}, failed_{false};
  std::atomic<uint64_t> reads_{0};
  mutable base::Mutex mutex_;
  std::vector<std::string> failures_ ABSL_GUARDED_BY(mutex_);
};

void FleetRebalanceTest::StartTrafficThenTheFourthDaemon(Traffic& traffic, std::vector<uint64_t>& progress) {
  ASSERT_TRUE(traffic.Start().ok());
  progress = traffic.AwaitProgress(std::vector<uint64_t>(kMaps, 0), 10);
  StartMember(kFirstDaemons);
}

// Every acknowledged observation of map i is at `owner`, once: its count there is exactly its
// writer's acknowledged batches' (no batch lost or applied twice).
void ExpectAcknowledgedAt(const Traffic& traffic, int i, const std::string& owner, bool moved) {
  const std::string map = MapName(i);
  const IngestSession& session = traffic.session(i);
  EXPECT_EQ(session.totals().acknowledged, session.totals().sent) << map;
  EXPECT_EQ(session.unacknowledged(), 0u) << map;
  // A moved map's writer was told to retry (its stream ended) and resent to the new owner.
  if (moved) {
    EXPECT_GE(session.totals().reconnects, 1u) << map;
  }
  auto stats = ClientOf(owner, 4).GetMapStats(map);
  ASSERT_TRUE(stats.ok()) << map << " at " << owner << ": " << stats.status();
  // Each acknowledged batch (5 observations) applied exactly once: a duplicate's ack (a resend of a
  // batch whose first ack was lost, as on a kill -9) accepts nothing because it was applied before.
  EXPECT_EQ(stats->observations(), 5 * session.totals().acknowledged) << map << (moved ? " (moved)" : "");
  EXPECT_EQ(session.totals().accepted, 5 * (session.totals().acknowledged - session.totals().duplicates)) << map;
}

TEST_F(FleetRebalanceTest, AFourthDaemonTakesExactlyTheMapsItNowOwnsWhileWritersKeepSending) {
  const std::set<std::string> moving = Moving();
  ASSERT_FALSE(moving.empty()) << "30 maps over 4 daemons: some move to the new one";
  for (const std::string& map : moving) ASSERT_EQ(after_->Owner(map), members_[kFirstDaemons].grpc) << map;
  const std::vector<std::map<std::string, v1::Map>> initial = HeldMaps(kFirstDaemons);

  Traffic traffic(proxy_->grpc_address());
  ASSERT_TRUE(traffic.Start().ok());
  std::vector<uint64_t> progress = traffic.AwaitProgress(std::vector<uint64_t>(kMaps, 0), 10);
  (void)progress;

  StartMember(kFirstDaemons);
  ASSERT_FALSE(HasFatalFailure());
  const std::string daemons = absl::StrJoin(Names(kFirstDaemons + 1), ",");
  // The maps it would move are the MISPLACED ones of the new list.
  const RunResult plan = Fremenctl({"fleet", "rebalance", "--daemons", daemons, "--dry-run"});
  ASSERT_EQ(plan.exit_code, 0) << plan.err;
  EXPECT_EQ(std::count(plan.out.begin(), plan.out.end(), '\n'), static_cast<long>(moving.size())) << plan.out;
  for (const std::string& map : moving) EXPECT_THAT(plan.out, HasSubstr(absl::StrCat(map, " ")));

  const RunResult rebalance = Fremenctl({"fleet", "rebalance", "--daemons", daemons, "--proxy-command",
                                         proxy_->ReloadCommand(Proxied(kFirstDaemons + 1)), "--proxy",
                                         proxy_->grpc_address()});
  ASSERT_EQ(rebalance.exit_code, 0) << rebalance.out << rebalance.err << proxy_->ErrorLog();
  EXPECT_THAT(rebalance.out, HasSubstr(absl::StrCat("moved ", moving.size(), " maps")));
  // The writers go on at the new owners: ten more batches acknowledged on every map from now.
  for (int i = 0; i < kMaps; ++i) progress[i] = traffic.Acknowledged(i);
  traffic.AwaitProgress(progress, 10);
  traffic.Stop();
  EXPECT_THAT(traffic.failures(), ::testing::IsEmpty());
  EXPECT_GT(traffic.reads(), 0u);

  const std::vector<std::map<std::string, v1::Map>> held = HeldMaps(kFirstDaemons + 1);
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    const std::string owner = after_->Owner(map);
    for (int d = 0; d <= kFirstDaemons; ++d) {
      EXPECT_EQ(held[d].count(map), members_[d].grpc == owner ? 1u : 0u) << map << " on " << members_[d].grpc;
    }
    if (!moving.contains(map)) {
      // Untouched: the very map created at the start, where it was.
      for (int d = 0; d < kFirstDaemons; ++d) {
        if (members_[d].grpc != owner) continue;
        EXPECT_EQ(held[d].at(map).create_time().seconds(), initial[d].at(map).create_time().seconds()) << map;
      }
    }
    ExpectAcknowledgedAt(traffic, i, owner, moving.contains(map));
    if (HasFatalFailure()) return;
  }
  // Nothing is misplaced, and a second run has nothing to do.
  const RunResult placed = Fremenctl({"fleet", "placement", "--address", daemons});
  EXPECT_EQ(placed.exit_code, 0) << placed.out << placed.err;
  const RunResult again = Fremenctl({"fleet", "rebalance", "--daemons", daemons});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_THAT(again.out, HasSubstr("nothing to move"));
}

TEST_F(FleetRebalanceTest, ARebalanceStoppedBeforeTheProxyIsFinishedByRunningItAgain) {
  const std::set<std::string> moving = Moving();
  ASSERT_FALSE(moving.empty());
  StartMember(kFirstDaemons);
  ASSERT_FALSE(HasFatalFailure());
  const std::string daemons = absl::StrJoin(Names(kFirstDaemons + 1), ",");
  // No --proxy-command: the copies are made and committed, then it stops and says what to do.
  const RunResult first = Fremenctl({"fleet", "rebalance", "--daemons", daemons});
  EXPECT_EQ(first.exit_code, 1);
  EXPECT_THAT(first.out, HasSubstr("deploy/nginx/render.py"));
  EXPECT_THAT(first.out, HasSubstr("--proxy-reloaded"));
  const Client proxy = ClientOf(proxy_->grpc_address(), 1);
  for (const std::string& map : moving) {
    // The proxy still routes to the old copy: it answers queries and refuses writes, retryably.
    auto got = proxy.GetMap(map);
    ASSERT_TRUE(got.ok()) << map << ": " << got.status();
    EXPECT_EQ(got->move_state(), v1::MAP_MOVE_STATE_MOVED) << map;
    EXPECT_EQ(got->moved_to(), members_[kFirstDaemons].grpc);
    client::IngestOptions options;
    options.reconnect_timeout = absl::ZeroDuration();
    auto session = proxy.OpenIngest(map, options);
    absl::Status written = session.status();
    if (session.ok()) {
      ScanBuilder scan(kStart);
      if (IsGrid(std::stoi(map.substr(std::string("building-").size())))) {
        scan.AddCell({1, 1, 0}, 1);
      } else {
        scan.AddNamedState("door", 1);
      }
      (void)(*session)->Send(*scan.Build());
      written = (*session)->Close();
    }
    EXPECT_EQ(written.code(), absl::StatusCode::kUnavailable) << map << ": " << written;
    EXPECT_THAT(written.message(), HasSubstr(absl::StrCat("map ", map, " is moving to another daemon; retry")));
  }
  // The operator's part is done by the second run's --proxy-command; it finishes the committed moves.
  const RunResult second = Fremenctl({"fleet", "rebalance", "--daemons", daemons, "--proxy-command",
                                      proxy_->ReloadCommand(Proxied(kFirstDaemons + 1)), "--proxy",
                                      proxy_->grpc_address()});
  ASSERT_EQ(second.exit_code, 0) << second.out << second.err;
  EXPECT_THAT(second.out, HasSubstr("copied already: finishing"));
  const std::vector<std::map<std::string, v1::Map>> held = HeldMaps(kFirstDaemons + 1);
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    for (int d = 0; d <= kFirstDaemons; ++d) {
      EXPECT_EQ(held[d].count(map), members_[d].grpc == after_->Owner(map) ? 1u : 0u) << map << " on " << d;
    }
    auto got = proxy.GetMap(map);
    ASSERT_TRUE(got.ok()) << map << ": " << got.status();
    EXPECT_EQ(got->move_state(), v1::MAP_MOVE_STATE_SERVING) << map;
  }
}

// A rebalance run on a thread that stops once its snapshots are copied (--test-pause-after-snapshot):
// Paused() waits until it is there (or has ended: false), Finish() lets it go on and returns how it
// ended.
class PausedRebalance {
 public:
  PausedRebalance(std::vector<std::string> args, const std::string& pause_file) : pause_(pause_file) {
    args.push_back("--test-pause-after-snapshot");
    args.push_back(pause_file);
    thread_ = std::thread([this, args] {
      RunOptions options;
      options.timeout = std::chrono::minutes(5);
      result_ = RunProgram(FREMENCTL_BINARY, args, options);
      ended_ = true;
    });
  }
  ~PausedRebalance() { (void)Finish(); }

  // Waits for the state, not for a time: the file appears once every snapshot is on its target.
  bool Paused() const {
    while (!std::filesystem::exists(pause_) && !ended_) absl::SleepFor(absl::Milliseconds(20));
    return std::filesystem::exists(pause_);
  }
  const RunResult& Finish() {
    std::error_code ignored;
    std::filesystem::remove(pause_, ignored);
    if (thread_.joinable()) thread_.join();
    return result_;
  }

 private:
  const std::string pause_;
  std::thread thread_;
  std::atomic<bool> ended_{false};
  RunResult result_;
};

// The number in "copied the tail of MAP to ... (N batches", or -1 when the output has no such line.
long TailBatches(const std::string& out, const std::string& map) {
  const std::string prefix = absl::StrCat("copied the tail of ", map, " to ");
  const size_t at = out.find(prefix);
  if (at == std::string::npos) return -1;
  const size_t open = out.find('(', at);
  return open == std::string::npos ? -1 : std::strtol(out.c_str() + open + 1, nullptr, 10);
}

TEST_F(FleetRebalanceTest, WritesAreAcceptedWhileTheSnapshotsAreCopiedAndTheTailsCarryThem) {
  const std::set<std::string> moving = Moving();
  ASSERT_FALSE(moving.empty());
  Traffic traffic(proxy_->grpc_address());
  std::vector<uint64_t> progress;
  StartTrafficThenTheFourthDaemon(traffic, progress);
  ASSERT_FALSE(HasFatalFailure());

  PausedRebalance run(RebalanceArgs(), dir_.Path("paused"));
  if (!run.Paused()) FAIL() << "the rebalance ended before its pause: " << run.Finish().out << run.Finish().err;
  // Every snapshot is on the new daemon, waiting for its tail; the sources take writes meanwhile.
  const std::vector<std::map<std::string, v1::Map>> held = HeldMaps(kFirstDaemons + 1);
  for (const std::string& map : moving) {
    const int source = MemberAt(before_->Owner(map));
    ASSERT_GE(source, 0);
    EXPECT_EQ(held[source].at(map).move_state(), v1::MAP_MOVE_STATE_COPYING) << map;
    ASSERT_TRUE(held[kFirstDaemons].contains(map)) << map;
    EXPECT_EQ(held[kFirstDaemons].at(map).move_state(), v1::MAP_MOVE_STATE_INCOMING) << map;
  }
  // Ten more batches acknowledged on every map — the moving ones' by their sources, where the
  // proxy still routes them — while the snapshots are copied already.
  for (int i = 0; i < kMaps; ++i) progress[i] = traffic.Acknowledged(i);
  traffic.AwaitProgress(progress, 10);
  for (const std::string& map : moving) {
    auto at_source = ClientOf(before_->Owner(map), 4).GetMapStats(map);
    auto in_snapshot = ClientOf(members_[kFirstDaemons].grpc, 4).GetMapStats(map);
    ASSERT_TRUE(at_source.ok() && in_snapshot.ok()) << map;
    EXPECT_GT(at_source->observations(), in_snapshot->observations()) << map;
  }

  const RunResult& rebalance = run.Finish();
  ASSERT_EQ(rebalance.exit_code, 0) << rebalance.out << rebalance.err << proxy_->ErrorLog();
  // Each tail carried the batches acknowledged during the pause (and before the writes stopped).
  for (const std::string& map : moving) EXPECT_GE(TailBatches(rebalance.out, map), 10) << map << "\n" << rebalance.out;
  for (int i = 0; i < kMaps; ++i) progress[i] = traffic.Acknowledged(i);
  traffic.AwaitProgress(progress, 10);
  traffic.Stop();
  EXPECT_THAT(traffic.failures(), ::testing::IsEmpty());
  for (int i = 0; i < kMaps; ++i) {
    ExpectAcknowledgedAt(traffic, i, after_->Owner(MapName(i)), moving.contains(MapName(i)));
    if (HasFatalFailure()) return;
  }
}

TEST_F(FleetRebalanceTest, AKill9OfASourceMidMoveLosesNothingOnceTheRebalanceRunsAgain) {
  const std::set<std::string> moving = Moving();
  ASSERT_FALSE(moving.empty());
  Traffic traffic(proxy_->grpc_address());
  std::vector<uint64_t> progress;
  StartTrafficThenTheFourthDaemon(traffic, progress);
  ASSERT_FALSE(HasFatalFailure());

  {
    PausedRebalance run(RebalanceArgs(), dir_.Path("paused"));
    if (!run.Paused()) FAIL() << "the rebalance ended before its pause: " << run.Finish().out << run.Finish().err;
    // kill -9 of a source between its snapshots and their tails, its writers sending; it restarts.
    const int victim = MemberAt(before_->Owner(*moving.begin()));
    ASSERT_GE(victim, 0);
    members_[victim].process->Kill();
    StartMember(victim);
    ASSERT_FALSE(HasFatalFailure());
    // The restarted source has no record of what was written since its snapshots: those tails
    // cannot be sent, so the run gives every copy up and the maps stay where they were.
    const RunResult& first = run.Finish();
    EXPECT_EQ(first.exit_code, 1) << first.out << first.err;
    EXPECT_THAT(first.err, HasSubstr("nothing was moved"));
  }
  const std::vector<std::map<std::string, v1::Map>> held = HeldMaps(kFirstDaemons + 1);
  EXPECT_THAT(held[kFirstDaemons], ::testing::IsEmpty());
  for (int i = 0; i < kMaps; ++i) {
    const int source = MemberAt(before_->Owner(MapName(i)));
    ASSERT_TRUE(held[source].contains(MapName(i))) << MapName(i);
    EXPECT_EQ(held[source].at(MapName(i)).move_state(), v1::MAP_MOVE_STATE_SERVING) << MapName(i);
  }

  const RunResult second = Fremenctl(RebalanceArgs());
  ASSERT_EQ(second.exit_code, 0) << second.out << second.err << proxy_->ErrorLog();
  EXPECT_THAT(second.out, HasSubstr(absl::StrCat("moved ", moving.size(), " maps")));
  for (int i = 0; i < kMaps; ++i) progress[i] = traffic.Acknowledged(i);
  traffic.AwaitProgress(progress, 10);
  traffic.Stop();
  EXPECT_THAT(traffic.failures(), ::testing::IsEmpty());
  const std::vector<std::map<std::string, v1::Map>> after = HeldMaps(kFirstDaemons + 1);
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    for (int d = 0; d <= kFirstDaemons; ++d) {
      EXPECT_EQ(after[d].count(map), members_[d].grpc == after_->Owner(map) ? 1u : 0u) << map << " on " << d;
    }
    ExpectAcknowledgedAt(traffic, i, after_->Owner(map), moving.contains(map));
    if (HasFatalFailure()) return;
  }
}

}  // namespace
}  // namespace fremen::testing
