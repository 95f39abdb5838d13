// End-to-end tests of the operators' checks (storage/README.md, "Verification"): `fremenctl check MAP` (AdminService.CheckMap)
// against a serving fremend, `fremend --verify` against a stopped data directory, the
// verification of a backup before `fremenctl restore` creates anything, and `fremenctl salvage`
// (AdminService.SalvageMap) of a map that failed to open. Damage is done to the
// files themselves, as a disk would: bytes flipped in a log segment, a page of a shard zeroed.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/lib/client.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

namespace fs = std::filesystem;
using ::fremen::client::Client;
using ::fremen::client::ScanBuilder;
using ::fremen::client::StateSet;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kStart = 1699920000;

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteAt(const std::string& path, uint64_t offset, const std::string& bytes) {
  const int fd = open(path.c_str(), O_WRONLY);
  ASSERT_GE(fd, 0) << path;
  ASSERT_EQ(pwrite(fd, bytes.data(), bytes.size(), static_cast<off_t>(offset)), static_cast<ssize_t>(bytes.size()));
  close(fd);
}

// Zeroes the page in the middle of an LMDB file (4 KiB pages).
void ZeroMiddlePage(const std::string& path) {
  const uint64_t pages = fs::file_size(path) / 4096;
  ASSERT_GT(pages, 16u) << path;
  WriteAt(path, pages / 2 * 4096, std::string(4096, '\0'));
}

class CheckTest : public DaemonTest {
 protected:
  void SetUp() override { Start(); }

  void Start(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {"--backup-dir", dir_.Path("backups"), "--shards", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    StartDaemon(args);
    if (HasFatalFailure()) return;
    client::ConnectionOptions options;
    options.address = daemon_->address();
    client_.emplace(*Client::Connect(options));
    admin_ = v1::AdminService::NewStub(daemon_->NewChannel());
  }

  RunResult Fremenctl(const std::vector<std::string>& args) {
    RunOptions options;
    options.env = {{"FREMEN_ADDRESS", daemon_->address()}};
    return RunProgram(FREMENCTL_BINARY, args, options);
  }
  RunResult Verify() { return RunFremend({"--data-dir", data_dir(), "--verify"}); }

  // A grid of nx × ny cells, every one changed (`scans` scans of alternating patches), so that its
  // shard holds many LMDB pages.
  void MakeGrid(const std::string& map, uint32_t nx, uint32_t ny, int scans) {
    ASSERT_TRUE(client_->CreateMap(GridMapSpec(map, nx, ny, 0.1)).ok());
    auto session = client_->OpenIngest(map);
    ASSERT_TRUE(session.ok()) << session.status();
    for (int i = 0; i < scans; ++i) {
      ScanBuilder scan(kStart + i * 3600.0);
      scan.SetPatchBytes({0, 0, 0}, {nx, ny, 1}, std::string(uint64_t{nx} * ny, i % 2 ? '\xff' : '\0'));
      ASSERT_TRUE((*session)->Send(*scan.Build()).ok());
    }
    ASSERT_TRUE((*session)->Close(absl::Seconds(120)).ok());
  }

  // The directory of a map of the (stopped) daemon's data directory: the only one under maps/.
  std::string OnlyMapDir() const {
    std::vector<fs::path> dirs;
    for (const auto& e : fs::directory_iterator(data_dir() + "/maps")) dirs.push_back(e.path());
    EXPECT_EQ(dirs.size(), 1u);
    return dirs.empty() ? "" : dirs.front().string();
  }

  std::optional<Client> client_;
  std::unique_ptr<v1::AdminService::Stub> admin_;
};

TEST_F(CheckTest, FremenctlCheckOfAHealthyMapExitsZeroWithASummary) {
  MakeGrid("lab", 64, 32, 6);
  const RunResult r = Fremenctl({"check", "lab"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("map lab: 1 shards, "));
  EXPECT_THAT(r.out, HasSubstr("log 1 segments, 6 records, LSN 1..6"));
  EXPECT_THAT(r.out, HasSubstr(": clean\n"));
  // The map still serves and takes writes after the check.
  auto session = client_->OpenIngest("lab");
  ASSERT_TRUE(session.ok());
  ASSERT_TRUE((*session)->Send(*ScanBuilder(kStart + 7 * 3600.0).AddCell({1, 1, 0}, 1.0f).Build()).ok());
  ASSERT_TRUE((*session)->Close(absl::Seconds(30)).ok());
  const RunResult json = Fremenctl({"check", "--map", "lab", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_THAT(json.out, HasSubstr("\"clean\":true"));
  EXPECT_THAT(json.out, HasSubstr("\"last_lsn\":\"7\""));
}

TEST_F(CheckTest, CheckMapNamesTheFieldOfBadInput) {
  v1::CheckMapRequest request;
  v1::CheckMapResponse response;
  grpc::Status status = admin_->CheckMap(CallContext().get(), request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("map"));
  request.set_map("no-such-map");
  status = admin_->CheckMap(CallContext().get(), request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(status.error_message(), HasSubstr("no-such-map"));
  const RunResult r = Fremenctl({"check", "no-such-map"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("no-such-map"));
}

TEST_F(CheckTest, AReadTokenIsEnoughToCheck) {
  StopDaemon();
  Start({"--tokens-file", dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n")});
  v1::CheckMapRequest request;
  request.set_map("nothing");
  v1::CheckMapResponse response;
  EXPECT_EQ(admin_->CheckMap(CallContext().get(), request, &response).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  // Past authorization with the read token: the map is looked up (and does not exist).
  EXPECT_EQ(
      admin_->CheckMap(CallContext({{"authorization", "Bearer reader-token"}}).get(), request, &response).error_code(),
      grpc::StatusCode::NOT_FOUND);
}

TEST_F(CheckTest, SalvageNeedsAWriteToken) {
  StopDaemon();
  Start({"--tokens-file", dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n")});
  v1::SalvageMapRequest request;
  request.set_map("nothing");
  v1::SalvageMapResponse response;
  const grpc::Status reader =
      admin_->SalvageMap(CallContext({{"authorization", "Bearer reader-token"}}).get(), request, &response);
  EXPECT_EQ(reader.error_code(), grpc::StatusCode::PERMISSION_DENIED) << reader.error_message();
  // Past authorization with the write token: the map is looked up (and does not exist).
  const grpc::Status status =
      admin_->SalvageMap(CallContext({{"authorization", "Bearer writer-token"}}).get(), request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
  EXPECT_THAT(status.error_message(), HasSubstr("nothing"));
  request.clear_map();
  const grpc::Status unnamed =
      admin_->SalvageMap(CallContext({{"authorization", "Bearer writer-token"}}).get(), request, &response);
  EXPECT_EQ(unnamed.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << unnamed.error_message();
}

TEST_F(CheckTest, FremendVerifyOfAStoppedDataDirectory) {
  MakeGrid("lab", 64, 32, 6);
  // Refused while the daemon holds the data directory.
  const RunResult busy = Verify();
  EXPECT_EQ(busy.exit_code, 1);
  EXPECT_THAT(busy.err, HasSubstr("in use by another fremend"));
  StopDaemon();

  const RunResult clean = Verify();
  ASSERT_EQ(clean.exit_code, 0) << clean.out << clean.err;
  EXPECT_THAT(clean.out, HasSubstr("map lab: clean"));
  EXPECT_THAT(clean.out, HasSubstr("summary: 1 maps verified, 0 with problems"));

  // A record in the middle of the log damaged: the report names the segment.
  std::vector<fs::path> segments;
  for (const auto& e : fs::directory_iterator(OnlyMapDir() + "/wal")) segments.push_back(e.path());
  ASSERT_EQ(segments.size(), 1u);
  const std::string segment = segments.front().string();
  const uint64_t size = fs::file_size(segment);
  std::string byte = ReadAll(segment).substr(size / 2, 1);
  byte[0] ^= 0x40;
  WriteAt(segment, size / 2, byte);
  const RunResult damaged = Verify();
  EXPECT_EQ(damaged.exit_code, 1) << damaged.out << damaged.err;
  EXPECT_THAT(damaged.out, HasSubstr(absl::StrCat("map lab: wal/", segments.front().filename().string(), ": byte ")));
  EXPECT_THAT(damaged.out, HasSubstr("summary: 1 maps verified, 1 with problems"));

  // A zeroed page of the shard (LMDB aborts on it): named too, and the check goes on.
  ZeroMiddlePage(OnlyMapDir() + "/shard-0/data.mdb");
  const RunResult zeroed = Verify();
  EXPECT_EQ(zeroed.exit_code, 1);
  EXPECT_THAT(zeroed.out, HasSubstr("map lab: shard-0/data.mdb: "));
  EXPECT_THAT(zeroed.out, HasSubstr("summary: 1 maps verified"));
  EXPECT_TRUE(fs::exists(segment));  // nothing was removed or cut
  EXPECT_EQ(fs::file_size(segment), size);
}

TEST_F(CheckTest, ARestoreOfADamagedBackupIsDataLossAndCreatesNoMap) {
  MakeGrid("lab", 128, 64, 4);
  RunResult backup = Fremenctl({"backup", "--map", "lab", "--to", "copy"});
  ASSERT_EQ(backup.exit_code, 0) << backup.err;
  ZeroMiddlePage(dir_.Path("backups") + "/copy/shard-0/data.mdb");

  v1::RestoreMapRequest request;
  request.set_map("restored");
  request.set_directory("copy");
  v1::RestoreMapResponse response;
  const grpc::Status status = admin_->RestoreMap(CallContext().get(), request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DATA_LOSS) << status.error_message();
  EXPECT_THAT(status.error_message(), HasSubstr("shard-0/data.mdb"));
  const RunResult restore = Fremenctl({"restore", "--from", "copy", "--as", "restored2"});
  EXPECT_EQ(restore.exit_code, 1);
  EXPECT_THAT(restore.err, HasSubstr("shard-0/data.mdb"));
  const RunResult maps = Fremenctl({"maps", "list"});
  ASSERT_EQ(maps.exit_code, 0) << maps.err;
  EXPECT_THAT(maps.out, HasSubstr("lab"));
  EXPECT_THAT(maps.out, Not(HasSubstr("restored")));
  EXPECT_EQ(std::distance(fs::directory_iterator(data_dir() + "/maps"), fs::directory_iterator()), 1);
  // The daemon still serves the map it has.
  EXPECT_EQ(Fremenctl({"check", "lab"}).exit_code, 0);
}

// Every cell of an nx × ny grid, row by row.
StateSet AllCells(uint32_t nx, uint32_t ny) {
  std::vector<client::Cell> cells;
  for (uint32_t y = 0; y < ny; ++y) {
    for (uint32_t x = 0; x < nx; ++x) cells.push_back({x, y, 0});
  }
  return StateSet::Cells(cells);
}

TEST_F(CheckTest, FremenctlSalvageServesWhatSurvivedAndLeavesTheDamagedMap) {
  constexpr uint32_t kX = 64, kY = 32;
  MakeGrid("lab", kX, kY, 6);
  {
    // One more occupied scan, so that no cell predicts 0.5 (which a lost cell does).
    auto session = client_->OpenIngest("lab");
    ASSERT_TRUE(session.ok()) << session.status();
    ScanBuilder scan(kStart + 6 * 3600.0);
    scan.SetPatchBytes({0, 0, 0}, {kX, kY, 1}, std::string(uint64_t{kX} * kY, '\xff'));
    ASSERT_TRUE((*session)->Send(*scan.Build()).ok());
    ASSERT_TRUE((*session)->Close(absl::Seconds(60)).ok());
  }
  const double t = kStart + 7 * 3600.0;
  auto before = client_->Predict("lab", AllCells(kX, kY), {t});
  ASSERT_TRUE(before.ok()) << before.status();
  ASSERT_TRUE(before->unobserved.empty());
  const float p = before->probability(0, 0);
  ASSERT_NE(p, 0.5f);  // a lost cell (0.5) must be told from a kept one
  for (uint32_t i = 0; i < kX * kY; ++i) ASSERT_EQ(before->probability(0, i), p) << "cell " << i;
  StopDaemon();
  const std::string file = OnlyMapDir() + "/shard-0/data.mdb";
  ZeroMiddlePage(file);
  const std::string damaged = ReadAll(file);

  Start();
  ASSERT_FALSE(HasFatalFailure());
  auto status = client_->GetServerStatus();
  ASSERT_TRUE(status.ok()) << status.status();
  ASSERT_EQ(status->failed_maps_size(), 1);
  ASSERT_EQ(status->failed_maps(0).map(), "lab");

  const RunResult r = Fremenctl({"salvage", "lab"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("map lab salvaged as lab-salvaged: "));
  EXPECT_THAT(r.out, HasSubstr("map lab: lost: shard-0/data.mdb: "));
  EXPECT_THAT(r.out, HasSubstr("map lab: shard-0: "));

  // The report, through the RPC: a second salvage under the same name is refused, naming the field.
  v1::SalvageMapRequest request;
  request.set_map("lab");
  request.set_new_map("lab-salvaged");
  v1::SalvageMapResponse again;
  grpc::Status refused = admin_->SalvageMap(CallContext().get(), request, &again);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::ALREADY_EXISTS) << refused.error_message();
  EXPECT_THAT(refused.error_message(), HasSubstr("new_map"));
  // A healthy map is not salvaged.
  request.set_map("lab-salvaged");
  request.set_new_map("");
  refused = admin_->SalvageMap(CallContext().get(), request, &again);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << refused.error_message();
  EXPECT_THAT(refused.error_message(), HasSubstr("map lab-salvaged is not damaged"));
  // The JSON report of another salvage (to another name) counts what the first one kept.
  const RunResult json = Fremenctl({"salvage", "lab", "--to", "lab-2", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_THAT(json.out, HasSubstr("\"name\":\"lab-2\""));
  auto second = client_->SalvageMap("lab", "lab-3");
  ASSERT_TRUE(second.ok()) << second.status();
  uint64_t kept = 0, lost = 0;
  for (const v1::DatabaseSalvage& d : second->shards(0).databases()) {
    if (d.name() == "dynamic") kept = d.kept(), lost = d.lost();
  }
  EXPECT_EQ(kept + lost, uint64_t{kX} * kY);
  EXPECT_GT(lost, 0u);

  // The salvaged map serves: every cell kept predicts as before, every lost one is unobserved.
  for (const std::string map : {"lab-salvaged", "lab-3"}) {
    auto after = client_->Predict(map, AllCells(kX, kY), {t});
    ASSERT_TRUE(after.ok()) << map << ": " << after.status();
    EXPECT_EQ(after->unobserved.size(), lost) << map;
    uint32_t same = 0;
    for (uint32_t i = 0; i < kX * kY; ++i) {
      const float q = after->probability(0, i);
      EXPECT_TRUE(q == p || q == 0.5f) << map << " cell " << i << ": " << q;
      same += q == p;
    }
    EXPECT_EQ(same, kept) << map;
  }
  // It takes writes.
  auto session = client_->OpenIngest("lab-salvaged");
  ASSERT_TRUE(session.ok()) << session.status();
  ASSERT_TRUE((*session)->Send(*ScanBuilder(t + 3600.0).AddCell({1, 1, 0}, 1.0f).Build()).ok());
  ASSERT_TRUE((*session)->Close(absl::Seconds(30)).ok());
  session->reset();

  // The damaged map is left as it was: failed, its file unchanged.
  EXPECT_EQ(ReadAll(file), damaged);
  status = client_->GetServerStatus();
  ASSERT_TRUE(status.ok());
  ASSERT_EQ(status->failed_maps_size(), 1);
  EXPECT_EQ(status->failed_maps(0).map(), "lab");

  // And after a restart the salvaged map is an ordinary map.
  StopDaemon();
  Start();
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(Fremenctl({"check", "lab-salvaged"}).exit_code, 0);
}

}  // namespace
}  // namespace fremen::testing
