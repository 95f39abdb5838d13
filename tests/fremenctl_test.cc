// End-to-end tests of fremenctl's daemon commands (maps, predict, top, anomalies, stats, update,
// operations, backup, restore, status, the global connection options): the real binary (FREMENCTL_BINARY) run
// against a real fremend, each command's output and exit code checked, and a bad-input case each
// with the message that says what to fix. Data is put in through the C++ client library.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/lib/client.h"
#include "tests/fremend_fixture.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Client;
using ::fremen::client::ScanBuilder;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kDay = 86400;
constexpr double kStart = 1699920000;  // midnight UTC

// 1 from 8:00 to 18:00 UTC.
float DayPattern(double t) {
  const double hour = std::fmod(t - kStart, kDay) / 3600;
  return hour >= 8 && hour < 18 ? 1.0f : 0.0f;
}

class FremenctlTest : public DaemonTest {
 protected:
  void SetUp() override {
    StartDaemon({"--backup-dir", dir_.Path("backups")});
    if (HasFatalFailure()) return;
    client::ConnectionOptions options;
    options.address = daemon_->address();
    client_.emplace(*Client::Connect(options));
  }

  // Runs fremenctl with `args` against the test's daemon (FREMEN_ADDRESS, before the variables
  // of `options.env`).
  RunResult Run(const std::vector<std::string>& args, RunOptions options = {}) {
    options.env.insert(options.env.begin(), {"FREMEN_ADDRESS", daemon_->address()});
    return RunProgram(FREMENCTL_BINARY, args, options);
  }
  // With FREMEN_TOKEN=`token`.
  RunResult RunWithToken(const std::vector<std::string>& args, const std::string& token) {
    RunOptions options;
    options.env = {{"FREMEN_TOKEN", token}};
    return Run(args, options);
  }

  void CreateGrid(const std::string& name, uint32_t nx = 20, uint32_t ny = 10) {
    RunResult r = Run({"maps", "create", name, "--resolution", "0.5", "--size", absl::StrCat(nx), absl::StrCat(ny)});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }

  // Two weeks of hourly scans of the day pattern in cell (2, 3) of `map`, each week followed by an
  // update, so that the model follows the pattern.
  void IngestTwoWeeks(const std::string& map) {
    for (int week = 0; week < 2; ++week) {
      auto session = client_->OpenIngest(map);
      ASSERT_TRUE(session.ok()) << session.status();
      for (int hour = 0; hour < 7 * 24; ++hour) {
        const double t = kStart + (week * 7 * 24 + hour) * 3600.0;
        ASSERT_TRUE((*session)->Send(*ScanBuilder(t).AddCell({2, 3, 0}, DayPattern(t)).Build()).ok());
      }
      ASSERT_TRUE((*session)->Close(absl::Seconds(60)).ok());
      RunResult r = Run({"update", "--map", map, "--wait"});
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
  }

  // A grid whose nx·ny cells all changed: its update job takes a while.
  void MakeDynamicGrid(const std::string& map, uint32_t nx, uint32_t ny) {
    CreateGrid(map, nx, ny);
    auto session = client_->OpenIngest(map);
    ASSERT_TRUE(session.ok()) << session.status();
    for (int i = 0; i < 3; ++i) {
      ScanBuilder scan(kStart + i * 3600.0);
      scan.SetPatchBytes({0, 0, 0}, {nx, ny, 1}, std::string(uint64_t{nx} * ny, i % 2 ? '\xff' : '\0'));
      ASSERT_TRUE((*session)->Send(*scan.Build()).ok());
    }
    ASSERT_TRUE((*session)->Close(absl::Seconds(120)).ok());
  }

  std::optional<Client> client_;
};

// --- maps ---

TEST_F(FremenctlTest, MapsCreateListGetDelete) {
  CreateGrid("lab");
  RunResult generic = Run({"maps", "create", "doors", "--generic", "--max-order", "3", "--criterion", "squared"});
  ASSERT_EQ(generic.exit_code, 0) << generic.err;
  EXPECT_THAT(generic.out, HasSubstr("created map doors: generic"));

  RunResult list = Run({"maps", "list"});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_THAT(list.out, HasSubstr("doors"));
  EXPECT_THAT(list.out, HasSubstr("grid 20x10x1 cells of 0.5 m"));
  EXPECT_LT(list.out.find("doors"), list.out.find("lab"));  // name order

  RunResult get = Run({"maps", "get", "doors"});
  ASSERT_EQ(get.exit_code, 0) << get.err;
  EXPECT_THAT(get.out, HasSubstr("max_order: 3"));
  EXPECT_THAT(get.out, HasSubstr("criterion: squared"));
  EXPECT_THAT(get.out, HasSubstr("order_selection: margin 0.001"));  // the default
  RunResult margin = Run({"maps", "create", "gates", "--generic", "--order-selection", "margin", "--order-margin",
                          "0.003", "--criterion", "threshold"});
  ASSERT_EQ(margin.exit_code, 0) << margin.err;
  EXPECT_THAT(Run({"maps", "get", "gates"}).out, HasSubstr("order_selection: margin 0.003"));
  RunResult paper = Run({"maps", "create", "paper", "--generic", "--order-selection", "paper"});
  ASSERT_EQ(paper.exit_code, 0) << paper.err;
  EXPECT_THAT(Run({"maps", "get", "paper"}).out, HasSubstr("order_selection: paper"));
  EXPECT_EQ(Run({"maps", "create", "bad", "--generic", "--order-selection", "best"}).exit_code, 2);
  RunResult json = Run({"maps", "get", "lab", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_THAT(json.out, HasSubstr("\"resolution\":0.5"));

  RunResult del = Run({"maps", "delete", "doors", "--yes"});
  ASSERT_EQ(del.exit_code, 0) << del.err;
  EXPECT_THAT(Run({"maps", "list"}).out, Not(HasSubstr("doors")));
}

TEST_F(FremenctlTest, MapsBadInputSaysWhatToFix) {
  RunResult no_size = Run({"maps", "create", "lab", "--resolution", "0.5"});
  EXPECT_EQ(no_size.exit_code, 2);
  EXPECT_THAT(no_size.err, HasSubstr("needs --resolution METRES and --size X Y"));
  RunResult bad_name = Run({"maps", "create", "bad name!", "--generic"});
  EXPECT_EQ(bad_name.exit_code, 1);
  EXPECT_THAT(bad_name.err, HasSubstr("name"));
  CreateGrid("lab");
  RunResult taken = Run({"maps", "create", "lab", "--generic"});
  EXPECT_EQ(taken.exit_code, 1);
  EXPECT_THAT(taken.err, HasSubstr("pick another name"));
  RunResult missing = Run({"maps", "get", "nope"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.err, HasSubstr("map \"nope\" does not exist"));
  EXPECT_THAT(missing.err, HasSubstr("fremenctl maps list"));
  RunResult unconfirmed = Run({"maps", "delete", "lab"});
  EXPECT_EQ(unconfirmed.exit_code, 2);
  EXPECT_THAT(unconfirmed.err, HasSubstr("add --yes"));
  EXPECT_THAT(Run({"maps", "list"}).out, HasSubstr("lab"));  // still there
  EXPECT_EQ(Run({"maps"}).exit_code, 2);                  // a subcommand is required
}

// --- queries ---

TEST_F(FremenctlTest, PredictFollowsThePattern) {
  CreateGrid("lab");
  IngestTwoWeeks("lab");
  RunResult r = Run({"predict", "--map", "lab", "--cell", "2,3", "--cell", "9,9", "--time", "2023-11-28T12:00:00Z", "--time",
                     absl::StrCat(kStart + 14 * kDay), "--confidence", "0.5"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string header, noon, unobserved, midnight;
  std::getline(lines, header);
  std::getline(lines, noon);
  std::getline(lines, unobserved);
  std::getline(lines, midnight);
  EXPECT_THAT(header, HasSubstr("TIME"));
  EXPECT_THAT(noon, HasSubstr("2023-11-28T12:00:00Z  2,3"));
  EXPECT_GT(std::stod(noon.substr(noon.find("2,3") + 22)), 0.7) << noon;
  EXPECT_THAT(noon, ::testing::EndsWith("  1"));
  EXPECT_THAT(unobserved, HasSubstr("(never observed)"));
  EXPECT_LT(std::stod(midnight.substr(midnight.find("2,3") + 22)), 0.3) << midnight;
}

TEST_F(FremenctlTest, PredictBadInputSaysWhatToFix) {
  CreateGrid("lab");
  RunResult cell = Run({"predict", "--map", "lab", "--cell", "2", "--time", "now"});
  EXPECT_EQ(cell.exit_code, 2);
  EXPECT_THAT(cell.err, HasSubstr("cell \"2\" is not X,Y or X,Y,Z"));
  RunResult time = Run({"predict", "--map", "lab", "--cell", "2,3", "--time", "tomorrow"});
  EXPECT_EQ(time.exit_code, 2);
  EXPECT_THAT(time.err, HasSubstr("RFC 3339"));
  RunResult none = Run({"predict", "--map", "lab", "--time", "now"});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_THAT(none.err, HasSubstr("name the states with one of --cell"));
  RunResult outside = Run({"predict", "--map", "lab", "--id", "3", "--time", "now"});
  EXPECT_EQ(outside.exit_code, 1);  // ids are for generic maps: the daemon says so
  EXPECT_FALSE(outside.err.empty());
  RunResult unknown = Run({"predict", "--map", "nope", "--cell", "1,1", "--time", "now"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.err, HasSubstr("fremenctl maps list"));
}

TEST_F(FremenctlTest, TopRanksTheGroup) {
  ASSERT_EQ(Run({"maps", "create", "doors", "--generic"}).exit_code, 0);
  auto session = client_->OpenIngest("doors");
  ASSERT_TRUE(session.ok());
  for (int i = 0; i < 24; ++i) {
    ScanBuilder scan(kStart + i * 3600.0);
    scan.AddState(1, 1, "front", "entrances")
        .AddState(2, 0, "back", "entrances")
        .AddState(3, i % 2, "side", "entrances");
    ASSERT_TRUE((*session)->Send(*scan.Build()).ok());
  }
  ASSERT_TRUE((*session)->Close(absl::Seconds(30)).ok());
  RunResult r = Run({"top", "--map", "doors", "--group", "entrances", "-n", "2", "--time", absl::StrCat(kStart + kDay)});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("1     1                     front"));
  EXPECT_THAT(r.out, Not(HasSubstr("back")));  // only the top 2

  RunResult zero = Run({"top", "--map", "doors", "--group", "entrances", "-n", "0"});
  EXPECT_EQ(zero.exit_code, 2);
  EXPECT_THAT(zero.err, HasSubstr("-n"));
  RunResult group = Run({"top", "--map", "doors", "--group", "windows"});
  EXPECT_EQ(group.exit_code, 1);
  EXPECT_THAT(group.err, HasSubstr("no group \"windows\""));
}

TEST_F(FremenctlTest, StatesListsTheNamedStatesByName) {
  ASSERT_EQ(Run({"maps", "create", "doors", "--generic"}).exit_code, 0);
  auto session = client_->OpenIngest("doors");
  ASSERT_TRUE(session.ok());
  ScanBuilder scan(kStart);
  scan.AddState(1, 1, "front", "entrances").AddState(2, 0, "back", "entrances").AddState(3, 1, "kitchen-light", "lights");
  ASSERT_TRUE((*session)->Send(*scan.Build()).ok());
  ASSERT_TRUE((*session)->Close(absl::Seconds(30)).ok());
  RunResult all = Run({"states", "--map", "doors"});
  ASSERT_EQ(all.exit_code, 0) << all.err;
  const size_t back = all.out.find("back"), front = all.out.find("front"), light = all.out.find("kitchen-light");
  ASSERT_NE(back, std::string::npos) << all.out;
  ASSERT_NE(front, std::string::npos) << all.out;
  ASSERT_NE(light, std::string::npos) << all.out;
  EXPECT_LT(back, front);  // by name
  EXPECT_LT(front, light);
  RunResult lights = Run({"states", "--map", "doors", "--group", "lights"});
  ASSERT_EQ(lights.exit_code, 0) << lights.err;
  EXPECT_THAT(lights.out, HasSubstr("kitchen-light"));
  EXPECT_THAT(lights.out, Not(HasSubstr("front")));
  RunResult missing = Run({"states", "--map", "doors", "--group", "windows"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.err, HasSubstr("no group \"windows\""));
}

TEST_F(FremenctlTest, AnomaliesFlagsWhatContradictsThePattern) {
  CreateGrid("lab");
  IngestTwoWeeks("lab");
  RunResult r =
      Run({"anomalies", "--map", "lab", "--cell", "2,3", "--cell", "2,3", "--value", "0", "--value", "1", "--time",
           "2023-11-28T12:00:00Z", "--confidence", "0.7"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("yes"));
  EXPECT_THAT(r.out, HasSubstr("1 of 2 observations anomalous at confidence 0.7"));

  RunResult mismatch = Run({"anomalies", "--map", "lab", "--cell", "2,3", "--cell", "2,4", "--value", "0", "--time", "now"});
  EXPECT_EQ(mismatch.exit_code, 2);
  EXPECT_THAT(mismatch.err, HasSubstr("give one --value per state: 2 states but 1 values"));
  RunResult confidence = Run({"anomalies", "--map", "lab", "--cell", "2,3", "--value", "0", "--time", "now", "--confidence", "0.2"});
  EXPECT_EQ(confidence.exit_code, 2);
  EXPECT_THAT(confidence.err, HasSubstr("--confidence"));
}

TEST_F(FremenctlTest, StatsCountTheObservations) {
  CreateGrid("lab");
  IngestTwoWeeks("lab");
  RunResult r = Run({"stats", "--map", "lab"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("states: 1 (1 dynamic)"));
  EXPECT_THAT(r.out, HasSubstr("observations: 336"));
  RunResult json = Run({"stats", "--map", "lab", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_THAT(json.out, HasSubstr("\"observations\":\"336\""));
  RunResult missing = Run({"stats", "--map", "nope"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.err, HasSubstr("map \"nope\" does not exist"));
  EXPECT_EQ(Run({"stats"}).exit_code, 2);  // --map is required
}

// --- update ---

TEST_F(FremenctlTest, UpdateStartsOrWaitsWithProgressAndSummary) {
  CreateGrid("lab");
  RunResult started = Run({"update", "--map", "lab"});
  ASSERT_EQ(started.exit_code, 0) << started.err;
  EXPECT_THAT(started.out, HasSubstr("started operations/"));
  EXPECT_THAT(started.out, HasSubstr("fremenctl update --map lab --wait"));

  MakeDynamicGrid("big", 512, 256);
  RunResult waited = Run({"update", "--map", "big", "--wait", "--poll-interval", "0.05", "--line-interval", "0"});
  ASSERT_EQ(waited.exit_code, 0) << waited.err;
  EXPECT_THAT(waited.out, HasSubstr("done: 131072 states published"));
  EXPECT_THAT(waited.out, HasSubstr("orders: "));
  // Not a terminal: plain progress lines, the last one at the total.
  EXPECT_THAT(waited.err, HasSubstr("update of big: done, 131072/131072 states (100%)"));
  EXPECT_THAT(waited.err, Not(HasSubstr("\r")));

  RunResult unknown = Run({"update", "--map", "nope", "--wait"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.err, HasSubstr("fremenctl maps list"));
  EXPECT_EQ(Run({"update", "--map", "lab", "--poll-interval", "0"}).exit_code, 2);
}

TEST_F(FremenctlTest, OperationsListWaitAndCancel) {
  // Updates run one at a time: small's job is queued behind big's and cancelled there, at once (a
  // queued job ends as it is cancelled), so fremenctl then follows a job whose end is known. What
  // is left to timing is only that big's job (512k states) outlasts two back-to-back calls.
  MakeDynamicGrid("big", 1024, 512);
  CreateGrid("small");
  auto running = client_->RunUpdate("big");
  ASSERT_TRUE(running.ok()) << running.status();
  auto queued = client_->RunUpdate("small");
  ASSERT_TRUE(queued.ok()) << queued.status();
  ASSERT_EQ(queued->stage(), v1::OPERATION_STAGE_QUEUED);
  // Cancelled by the next call, while big's job still runs: not through fremenctl, whose start
  // could take longer than big's job on a loaded machine.
  auto cancelled = client_->CancelOperation("small", queued->name());
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  ASSERT_TRUE(cancelled->done());
  ASSERT_EQ(cancelled->error().code(), 1 /* CANCELLED */);
  // fremenctl's cancel of a job that has ended answers it unchanged.
  RunResult cancel = Run({"operations", "cancel", queued->name(), "--map", "small"});
  ASSERT_EQ(cancel.exit_code, 0) << cancel.err;
  EXPECT_EQ(cancel.out, absl::StrCat(queued->name(), " small done: cancelled (RunUpdate)\n"));

  // Following a cancelled job exits 1 and says so, as `update --wait` does (the same code).
  RunResult wait_cancelled = Run({"operations", "wait", queued->name(), "--map", "small"});
  EXPECT_EQ(wait_cancelled.exit_code, 1) << wait_cancelled.out;
  EXPECT_THAT(wait_cancelled.err,
              HasSubstr(absl::StrCat("fremenctl operations wait: update of small (", queued->name(), ") was cancelled")));
  RunResult wait_done = Run({"operations", "wait", running->name(), "--map", "big", "--poll-interval", "0.05"});
  ASSERT_EQ(wait_done.exit_code, 0) << wait_done.err;
  EXPECT_THAT(wait_done.out, HasSubstr("done: 524288 states published"));

  RunResult list = Run({"operations", "list"});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_THAT(list.out, HasSubstr(absl::StrCat(running->name(), " big done: 524288 states published (RunUpdate)\n")));
  EXPECT_THAT(list.out, HasSubstr(absl::StrCat(queued->name(), " small done: cancelled (RunUpdate)\n")));
  RunResult only_small = Run({"operations", "list", "--map", "small", "--json"});
  ASSERT_EQ(only_small.exit_code, 0) << only_small.err;
  EXPECT_THAT(only_small.out, HasSubstr("\"map\":\"small\""));
  EXPECT_THAT(only_small.out, Not(HasSubstr("\"map\":\"big\"")));
  EXPECT_EQ(Run({"operations", "list", "--running"}).out, "");

  RunResult unknown = Run({"operations", "wait", "operations/update-nope-1", "--map", "nope"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.err, HasSubstr("fremenctl operations wait"));
  EXPECT_EQ(Run({"operations", "cancel", queued->name()}).exit_code, 2);  // --map is required
  EXPECT_EQ(Run({"operations"}).exit_code, 2);                           // a subcommand is required
}

// --- backup, restore ---

TEST_F(FremenctlTest, BackupAndRestore) {
  CreateGrid("lab");
  IngestTwoWeeks("lab");
  RunResult backup = Run({"backup", "--map", "lab", "--to", "nightly/lab"});
  ASSERT_EQ(backup.exit_code, 0) << backup.err;
  EXPECT_THAT(backup.out, HasSubstr("backed up map lab to " + dir_.Path("backups") + "/nightly/lab"));
  RunResult restore = Run({"restore", "--from", "nightly/lab", "--as", "lab-copy"});
  ASSERT_EQ(restore.exit_code, 0) << restore.err;
  EXPECT_THAT(restore.out, HasSubstr("restored map lab-copy from nightly/lab"));
  EXPECT_THAT(Run({"stats", "--map", "lab-copy"}).out, HasSubstr("observations: 336"));
}

TEST_F(FremenctlTest, BackupAndRestoreBadInputSayWhatToFix) {
  CreateGrid("lab");
  ASSERT_EQ(Run({"backup", "--map", "lab", "--to", "once"}).exit_code, 0);
  RunResult again = Run({"backup", "--map", "lab", "--to", "once"});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.err, HasSubstr("pick a new directory name"));
  RunResult escape = Run({"backup", "--map", "lab", "--to", "../outside"});
  EXPECT_EQ(escape.exit_code, 1);
  EXPECT_THAT(escape.err, HasSubstr("relative to the daemon's backup root"));
  RunResult taken = Run({"restore", "--from", "once"});
  EXPECT_EQ(taken.exit_code, 1);
  EXPECT_THAT(taken.err, HasSubstr("--as NAME"));
  RunResult nothing = Run({"restore", "--from", "nowhere", "--as", "x"});
  EXPECT_EQ(nothing.exit_code, 1);
  EXPECT_THAT(nothing.err, HasSubstr("no backup"));
  EXPECT_EQ(Run({"backup", "--map", "lab"}).exit_code, 2);  // --to is required
}

// --- status and the connection options ---

TEST_F(FremenctlTest, StatusDescribesTheDaemon) {
  CreateGrid("lab");
  RunResult r = Run({"status"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("fremend 0."));
  EXPECT_THAT(r.out, HasSubstr("maps: 1"));
  EXPECT_THAT(r.out, HasSubstr("store: open"));
  RunResult json = Run({"status", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_THAT(json.out, HasSubstr("\"map_count\":\"1\""));
}

TEST_F(FremenctlTest, BenchRunsTheIngestLoadGeneratorAgainstTheDaemon) {
  // A small run: one stream of 100-cell scans into a 10³ grid, one window of half a second.
  RunResult r = Run({"bench", "ingest", "--", "--map", "bench", "--grid", "10", "--streams", "1", "--cells", "100",
                     "--warmup", "0.2", "--seconds", "0.5", "--repetitions", "1", "--predict-calls", "0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("cell-obs/s"));
  // The generator talked to this daemon: its map is there, with what it ingested.
  auto stats = client_->GetMapStats("bench");
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_GT(stats->observations(), 0u);

  RunResult bad = Run({"bench", "nosuch"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("nosuch not in {ingest,query}"));
  // The generator's own usage errors are its exit code.
  EXPECT_NE(Run({"bench", "ingest", "--", "--streams", "0"}).exit_code, 0);
}

TEST_F(FremenctlTest, BenchQueryMeasuresRegionsNextToTheirCeilingOfTheSameRun) {
  // A small map: 64² cells, two days of scans, two boxes of each output, no series, no Predict.
  RunResult r = Run({"bench", "query", "--", "--create", "--size=64", "--scans=8", "--region-reps=2",
                     "--series-reps=0", "--predict-calls=0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Each output's figure, then the same box of the empty map made beside it, then their ratio.
  for (const char* output : {"FLOAT", "UINT8"}) {
    EXPECT_THAT(r.out, HasSubstr(std::string("PredictRegion ") + output + " median"));
    EXPECT_THAT(r.out, HasSubstr(std::string("ceiling, the same box with nothing observed: PredictRegion ") + output));
  }
  EXPECT_THAT(r.out, HasSubstr("of the ceiling's rate"));
  auto filled = client_->GetMapStats("bench");
  ASSERT_TRUE(filled.ok()) << filled.status();
  EXPECT_EQ(filled->states(), 64u * 64u);
  auto empty = client_->GetMapStats("bench-unobserved");
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_EQ(empty->states(), 0u);
}

TEST_F(FremenctlTest, UnreachableDaemonSaysToStartItOrFixTheAddress) {
  const std::string nowhere = FreeLoopbackAddress();
  // The option after the subcommand wins over FREMEN_ADDRESS.
  RunResult r = Run({"status", "--address", nowhere, "--timeout", "5"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is fremend running at " + nowhere));
  EXPECT_THAT(r.err, HasSubstr("--address (or FREMEN_ADDRESS)"));
  EXPECT_EQ(Run({"status", "--timeout", "-1"}).exit_code, 2);
  RunResult ca = Run({"status", "--tls-ca", "/no/such/file.pem"});
  EXPECT_EQ(ca.exit_code, 2);
  EXPECT_THAT(ca.err, HasSubstr("--tls-ca"));
}

class FremenctlTlsTest : public FremenctlTest {
 protected:
  void SetUp() override {
    certificate_ = MakeTestCertificate(dir_);
    if (!certificate_) GTEST_SKIP() << "openssl cannot make a test certificate";
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = certificate_->cert_pem;
    StartDaemon({"--tls-cert-file", certificate_->cert_path, "--tls-key-file", certificate_->key_path},
                grpc::SslCredentials(ssl));
  }
  std::optional<TestCertificate> certificate_;
};

TEST_F(FremenctlTlsTest, TlsCaConnectsWithTls) {
  RunResult r = Run({"status", "--tls-ca", certificate_->cert_path});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("security: TLS"));
  RunResult plain = Run({"status", "--timeout", "5"});
  EXPECT_EQ(plain.exit_code, 1);
  EXPECT_THAT(plain.err, HasSubstr("is fremend running at"));
}

class FremenctlTokenTest : public FremenctlTest {
 protected:
  void SetUp() override { StartDaemon({"--tokens", "read:reader-token write:writer-token"}); }
};

TEST_F(FremenctlTokenTest, TokensComeFromTheOptionOrTheEnvironment) {
  RunResult anonymous = Run({"maps", "list"});
  EXPECT_EQ(anonymous.exit_code, 1);
  EXPECT_THAT(anonymous.err, HasSubstr("pass --token (or set FREMEN_TOKEN)"));
  RunResult created = Run({"maps", "create", "lab", "--generic", "--token", "writer-token"});
  ASSERT_EQ(created.exit_code, 0) << created.err;
  RunResult listed = RunWithToken({"maps", "list"}, "reader-token");
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_THAT(listed.out, HasSubstr("lab"));
  RunResult denied = RunWithToken({"maps", "delete", "lab", "--yes"}, "reader-token");
  EXPECT_EQ(denied.exit_code, 1);
  EXPECT_THAT(denied.err, HasSubstr("needs a write token"));
}

}  // namespace
}  // namespace fremen::testing
