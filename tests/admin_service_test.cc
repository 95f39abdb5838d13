// End-to-end tests of fremen.v1.AdminService against the real fremend: every RPC; the update job as
// an operation (two triggers make one job, progress reaches the total, cancellation of a queued
// job, kill -9 mid-job); bad inputs with their exact codes; token roles; backup and restore under a
// new name; and order selection on generated states of known true order (docs/model.md, "Order
// selection"): the job picks order 0, 1, 2 and 3 for states made of that many daily harmonics, as
// QueryService.GetStateModel then shows.
//
// Observations are written with storage::Store in the test process while the daemon is stopped
// (tests/store_writer.h), so the test does not depend on the ingest service.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <thread>

#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"
#include "tests/store_writer.h"

namespace fremen::testing {
namespace {

using ::testing::AllOf;
using ::testing::ElementsAre;
using ::testing::ElementsAreArray;
using ::testing::Ge;
using ::testing::HasSubstr;
using ::testing::Le;
using Metadata = std::vector<std::pair<std::string, std::string>>;

constexpr double kT0 = 1'700'006'400;  // a Monday 00:00 UTC; any origin would do
constexpr double kDay = 86400;

v1::Map GenericMap(const std::string& name) { return GenericMapSpec(name); }

v1::Map GridMap(const std::string& name, uint32_t nx, uint32_t ny) { return GridMapSpec(name, nx, ny, 0.05); }

class AdminServiceTest : public DaemonTest {
 protected:
  void SetUp() override {
    // DaemonTest::SetUp starts a daemon without the flags below; this fixture starts its own.
    Start();
  }
  // The daemon with the test's backup root, a daily update at 03:00 UTC (`scheduled`) and `extra`.
  void Start(const std::vector<std::string>& extra = {}, bool scheduled = true) {
    std::vector<std::string> args = {"--backup-dir", backup_dir()};
    if (scheduled) args.insert(args.end(), {"--update-schedule", "0 3 * * *", "--update-time-zone", "UTC"});
    args.insert(args.end(), extra.begin(), extra.end());
    StartDaemon(args);
    if (HasFatalFailure()) return;
    admin_ = v1::AdminService::NewStub(daemon_->NewChannel());
    maps_ = v1::MapService::NewStub(daemon_->NewChannel());
  }
  void Restart() {
    StopDaemon();
    Start();
  }
  std::string backup_dir() const { return dir_.Path("backups"); }

  void CreateMap(const v1::Map& map) {
    v1::CreateMapRequest request;
    *request.mutable_map() = map;
    v1::CreateMapResponse response;
    const grpc::Status status = maps_->CreateMap(CallContext().get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  // Stops the daemon, writes with the store, starts it again.
  void WriteStopped(const std::string& map, std::vector<storage::ObservationBatch> batches) {
    StopDaemon();
    const absl::Status written = WriteBatches(data_dir(), map, std::move(batches));
    ASSERT_TRUE(written.ok()) << written;
    Start();
  }
  // A grid whose every cell has been seen free and occupied: n dynamic states.
  void MakeDynamicGrid(const std::string& name, uint32_t nx, uint32_t ny) {
    CreateMap(GridMap(name, nx, ny));
    if (HasFatalFailure()) return;
    WriteStopped(name, {GridScan(nx, ny, kT0, 0.0f), GridScan(nx, ny, kT0 + 3600, 1.0f),
                        GridScan(nx, ny, kT0 + 7200, 0.0f)});
  }

  grpc::Status RunUpdate(const std::string& map, v1::Operation* op, const Metadata& metadata = {}) {
    v1::RunUpdateRequest request;
    request.set_map(map);
    return admin_->RunUpdate(CallContext(metadata).get(), request, op);
  }
  grpc::Status GetOperation(const std::string& name, v1::Operation* op, const std::string& map = "",
                            const Metadata& metadata = {}) {
    v1::GetOperationRequest request;
    request.set_name(name);
    request.set_map(map);
    return admin_->GetOperation(CallContext(metadata).get(), request, op);
  }
  grpc::Status Cancel(const std::string& name, v1::Operation* op, const Metadata& metadata = {}) {
    v1::CancelOperationRequest request;
    request.set_name(name);
    return admin_->CancelOperation(CallContext(metadata).get(), request, op);
  }
  grpc::Status List(const std::string& map, int page_size, const std::string& token,
                    v1::ListOperationsResponse* response, bool running_only = false) {
    v1::ListOperationsRequest request;
    request.set_map(map);
    request.set_page_size(page_size);
    request.set_page_token(token);
    request.set_running_only(running_only);
    return admin_->ListOperations(CallContext().get(), request, response);
  }
  grpc::Status Backup(const std::string& map, const std::string& directory, v1::BackupMapResponse* response,
                      const Metadata& metadata = {}) {
    v1::BackupMapRequest request;
    request.set_map(map);
    request.set_directory(directory);
    return admin_->BackupMap(CallContext(metadata).get(), request, response);
  }
  grpc::Status Restore(const std::string& map, const std::string& directory, v1::RestoreMapResponse* response,
                       const Metadata& metadata = {}) {
    v1::RestoreMapRequest request;
    request.set_map(map);
    request.set_directory(directory);
    return admin_->RestoreMap(CallContext(metadata).get(), request, response);
  }
  grpc::Status Status(v1::GetServerStatusResponse* response, const Metadata& metadata = {}) {
    return admin_->GetServerStatus(CallContext(metadata).get(), v1::GetServerStatusRequest(), response);
  }

  // Polls the operation until it is done; every answer seen goes to `seen` when given.
  v1::Operation AwaitDone(const std::string& name, std::vector<v1::Operation>* seen = nullptr) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
    v1::Operation op;
    while (std::chrono::steady_clock::now() < deadline) {
      const grpc::Status status = GetOperation(name, &op);
      EXPECT_TRUE(status.ok()) << status.error_message();
      if (!status.ok()) return op;
      if (seen != nullptr) seen->push_back(op);
      if (op.done()) return op;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));  // polling a real daemon
    }
    ADD_FAILURE() << name << " not done after 2 minutes";
    return op;
  }
  // RunUpdate and wait; the finished operation.
  v1::Operation Update(const std::string& map) {
    v1::Operation op;
    const grpc::Status status = RunUpdate(map, &op);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return AwaitDone(op.name());
  }

  std::unique_ptr<v1::AdminService::Stub> admin_;
  std::unique_ptr<v1::MapService::Stub> maps_;
};

// --- RunUpdate, GetOperation, ListOperations, CancelOperation ---

TEST_F(AdminServiceTest, RunUpdateReturnsAnOperationThatFinishes) {
  CreateMap(GenericMap("lab"));
  v1::Operation started;
  ASSERT_TRUE(RunUpdate("lab", &started).ok());
  EXPECT_EQ(started.name(), "operations/update-lab-1");
  EXPECT_EQ(started.map(), "lab");
  EXPECT_EQ(started.trigger(), "RunUpdate");
  EXPECT_GT(started.create_time().seconds(), 0);
  const v1::Operation done = AwaitDone(started.name());
  EXPECT_TRUE(done.done());
  EXPECT_EQ(done.stage(), v1::OPERATION_STAGE_DONE);
  EXPECT_EQ(done.error().code(), 0) << done.error().message();
  ASSERT_TRUE(done.has_update());
  EXPECT_EQ(done.update().states_published(), 0u);
  EXPECT_EQ(done.update().order_histogram_size(), 6);  // orders 0..L, L = 5
  EXPECT_GE(done.end_time().seconds(), done.create_time().seconds());
}

TEST_F(AdminServiceTest, RunUpdateNamesTheMapByHeaderToo) {
  CreateMap(GenericMap("lab"));
  v1::Operation op;
  ASSERT_TRUE(RunUpdate("", &op, {{"x-fremen-map", "lab"}}).ok());
  EXPECT_EQ(op.map(), "lab");
  const grpc::Status differ = RunUpdate("yard", &op, {{"x-fremen-map", "lab"}});
  EXPECT_EQ(differ.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(AdminServiceTest, BadUpdateRequests) {
  v1::Operation op;
  const grpc::Status unknown = RunUpdate("nowhere", &op);
  EXPECT_EQ(unknown.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(unknown.error_message(), HasSubstr("nowhere"));
  const grpc::Status missing = RunUpdate("", &op);
  EXPECT_EQ(missing.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(missing.error_message(), HasSubstr("map"));

  const grpc::Status no_op = GetOperation("operations/update-lab-99", &op);
  EXPECT_EQ(no_op.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Cancel("operations/update-lab-99", &op).error_code(), grpc::StatusCode::NOT_FOUND);
  const grpc::Status empty = GetOperation("", &op);
  EXPECT_EQ(empty.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(empty.error_message(), HasSubstr("name"));
  const grpc::Status malformed = GetOperation("update-lab-1", &op);
  EXPECT_EQ(malformed.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(malformed.error_message(), HasSubstr("name"));

  v1::ListOperationsResponse list;
  const grpc::Status negative = List("", -1, "", &list);
  EXPECT_EQ(negative.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(negative.error_message(), HasSubstr("page_size"));
  const grpc::Status token = List("", 10, "not-a-token", &list);
  EXPECT_EQ(token.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(token.error_message(), HasSubstr("page_token"));
}

TEST_F(AdminServiceTest, OperationOfAnotherMapIsNotFound) {
  CreateMap(GenericMap("lab"));
  const v1::Operation done = Update("lab");
  v1::Operation op;
  EXPECT_TRUE(GetOperation(done.name(), &op, "lab").ok());
  EXPECT_EQ(GetOperation(done.name(), &op, "yard").error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(GetOperation(done.name(), &op, "", {{"x-fremen-map", "yard"}}).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(AdminServiceTest, TwoTriggersMakeOneJobWhoseProgressReachesTheTotal) {
  constexpr uint32_t kNx = 1024, kNy = 512;  // 524,288 dynamic cells: the job takes a while
  MakeDynamicGrid("big", kNx, kNy);
  v1::Operation first, second;
  ASSERT_TRUE(RunUpdate("big", &first).ok());
  ASSERT_TRUE(RunUpdate("big", &second).ok());
  EXPECT_EQ(second.name(), first.name());
  v1::ListOperationsResponse running;
  ASSERT_TRUE(List("big", 10, "", &running, /*running_only=*/true).ok());
  EXPECT_LE(running.operations_size(), 1);

  std::vector<v1::Operation> seen;
  const v1::Operation done = AwaitDone(first.name(), &seen);
  ASSERT_EQ(done.error().code(), 0) << done.error().message();
  uint64_t last = 0;
  for (const v1::Operation& op : seen) {  // progress never goes back
    EXPECT_GE(op.progress().states_done(), last);
    last = op.progress().states_done();
    EXPECT_LE(op.progress().states_done(), kNx * kNy);
  }
  EXPECT_EQ(done.progress().states_done(), kNx * kNy);
  EXPECT_EQ(done.progress().states_total(), kNx * kNy);
  EXPECT_GT(done.progress().rate(), 0);
  EXPECT_EQ(done.update().states_published(), kNx * kNy);
  uint64_t histogram = 0;
  for (uint64_t n : done.update().order_histogram()) histogram += n;
  EXPECT_EQ(histogram, kNx * kNy);
  EXPECT_GT(done.update().duration_seconds(), 0);

  v1::ListOperationsResponse all;
  ASSERT_TRUE(List("", 10, "", &all).ok());
  ASSERT_EQ(all.operations_size(), 1);  // one job for two triggers
  EXPECT_THAT(daemon_->Log(), HasSubstr("update of map big: 524288 states in"));
}

TEST_F(AdminServiceTest, CancelQueuedUpdateEndsItCancelled) {
  MakeDynamicGrid("big", 1024, 512);
  CreateMap(GenericMap("small"));
  v1::Operation big, small, cancelled;
  ASSERT_TRUE(RunUpdate("big", &big).ok());
  ASSERT_TRUE(RunUpdate("small", &small).ok());  // updates run one at a time: queued behind big
  ASSERT_EQ(small.stage(), v1::OPERATION_STAGE_QUEUED);
  ASSERT_TRUE(Cancel(small.name(), &cancelled).ok());
  EXPECT_TRUE(cancelled.done());
  EXPECT_TRUE(cancelled.cancel_requested());
  EXPECT_EQ(cancelled.error().code(), grpc::StatusCode::CANCELLED);
  EXPECT_FALSE(cancelled.has_update());

  EXPECT_EQ(AwaitDone(big.name()).error().code(), 0);
  v1::Operation again;  // an operation that ended is answered unchanged
  ASSERT_TRUE(Cancel(big.name(), &again).ok());
  EXPECT_EQ(again.error().code(), 0);
  EXPECT_FALSE(again.cancel_requested());
}

TEST_F(AdminServiceTest, CancelRunningUpdateStopsItUnlessItPublishes) {
  MakeDynamicGrid("big", 1024, 512);
  v1::Operation op, answer;
  ASSERT_TRUE(RunUpdate("big", &op).ok());
  ASSERT_TRUE(Cancel(op.name(), &answer).ok());
  EXPECT_TRUE(answer.cancel_requested());
  const v1::Operation done = AwaitDone(op.name());
  // Which stage the cancellation finds depends on timing; what follows from it does not.
  if (answer.stage() == v1::OPERATION_STAGE_PUBLISHING) {
    EXPECT_THAT(answer.message(), HasSubstr("cannot cancel"));
    EXPECT_EQ(done.error().code(), 0);
    EXPECT_TRUE(done.has_update());
  } else {
    EXPECT_EQ(done.error().code(), grpc::StatusCode::CANCELLED);
    EXPECT_FALSE(done.has_update());
  }
}

TEST_F(AdminServiceTest, ListOperationsNewestFirstFilteredAndPaged) {
  CreateMap(GenericMap("a"));
  CreateMap(GenericMap("b"));
  std::vector<std::string> names;
  for (const char* map : {"a", "b", "a"}) names.push_back(Update(map).name());
  v1::ListOperationsResponse all;
  ASSERT_TRUE(List("", 0, "", &all).ok());
  ASSERT_EQ(all.operations_size(), 3);
  EXPECT_EQ(all.operations(0).name(), names[2]);
  EXPECT_EQ(all.operations(2).name(), names[0]);

  std::vector<std::string> paged;
  std::string token;
  do {
    v1::ListOperationsResponse page;
    ASSERT_TRUE(List("a", 1, token, &page).ok());
    ASSERT_LE(page.operations_size(), 1);
    for (const auto& op : page.operations()) paged.push_back(op.name());
    token = page.next_page_token();
  } while (!token.empty());
  EXPECT_THAT(paged, ElementsAre(names[2], names[0]));

  v1::ListOperationsResponse running;
  ASSERT_TRUE(List("", 10, "", &running, /*running_only=*/true).ok());
  EXPECT_EQ(running.operations_size(), 0);
}

TEST_F(AdminServiceTest, KilledMidJobTheMapStaysConsistentAndTheNextRunCompletes) {
  constexpr uint32_t kNx = 1024, kNy = 512;
  MakeDynamicGrid("big", kNx, kNy);
  v1::Operation op;
  ASSERT_TRUE(RunUpdate("big", &op).ok());
  // Kill it while it publishes (or, should the poll miss that short window, just after).
  while (op.stage() == v1::OPERATION_STAGE_QUEUED || op.stage() == v1::OPERATION_STAGE_RUNNING) {
    ASSERT_TRUE(GetOperation(op.name(), &op).ok());
  }
  daemon_->Kill();
  daemon_.reset();
  Start();
  const v1::Operation done = Update("big");
  ASSERT_EQ(done.error().code(), 0) << done.error().message();
  // Recovery repeats a publication whose log record was written, so this run has nothing left to
  // do; killed before the record, the run does it all. Either way every state is published now.
  EXPECT_THAT(done.update().states_published(), ::testing::AnyOf(0u, kNx * kNy));
  uint64_t histogram = 0;
  for (uint64_t n : done.update().order_histogram()) histogram += n;
  EXPECT_EQ(histogram, kNx * kNy);
  // Idempotent: without new observations a second run updates nothing and changes nothing.
  const v1::Operation again = Update("big");
  EXPECT_EQ(again.update().states_published(), 0u);
  EXPECT_THAT(again.update().order_histogram(), ::testing::ElementsAreArray(done.update().order_histogram()))
      << "the second run changed the orders";
  EXPECT_DOUBLE_EQ(again.update().prediction_error_after(), done.update().prediction_error_after());
}

// --- BackupMap, RestoreMap ---

TEST_F(AdminServiceTest, BackupThenRestoreUnderANewName) {
  CreateMap(GenericMap("lab"));
  std::vector<storage::ObservationBatch> batches;
  for (int i = 0; i < 100; ++i) batches.push_back(GenericScan({1, 2, 3}, {i % 2 * 1.0f, 1.0f, 0.5f}, kT0 + 60 * i));
  WriteStopped("lab", std::move(batches));

  v1::BackupMapResponse backup;
  const grpc::Status backed_up = Backup("lab", "nightly/lab", &backup);
  ASSERT_TRUE(backed_up.ok()) << backed_up.error_message();
  EXPECT_EQ(backup.path(), backup_dir() + "/nightly/lab");
  EXPECT_GT(backup.bytes(), 0u);
  EXPECT_TRUE(std::filesystem::exists(backup.path() + "/map.info"));
  EXPECT_EQ(Backup("lab", "nightly/lab", &backup).error_code(), grpc::StatusCode::ALREADY_EXISTS);

  v1::RestoreMapResponse restored;
  const grpc::Status restore = Restore("lab-copy", "nightly/lab", &restored);
  ASSERT_TRUE(restore.ok()) << restore.error_message();
  EXPECT_EQ(restored.map().name(), "lab-copy");
  EXPECT_EQ(restored.map().kind(), v1::MAP_KIND_GENERIC);
  EXPECT_EQ(Restore("lab-copy", "nightly/lab", &restored).error_code(), grpc::StatusCode::ALREADY_EXISTS);
  EXPECT_EQ(Restore("", "nightly/lab", &restored).error_code(), grpc::StatusCode::ALREADY_EXISTS);  // "lab" exists
  EXPECT_EQ(Restore("other", "nightly/nothing", &restored).error_code(), grpc::StatusCode::NOT_FOUND);
  const grpc::Status bad_name = Restore("bad name", "nightly/lab", &restored);
  EXPECT_EQ(bad_name.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad_name.error_message(), HasSubstr("map"));

  const auto listed = [&] {
    v1::ListMapsRequest request;
    v1::ListMapsResponse response;
    EXPECT_TRUE(maps_->ListMaps(CallContext().get(), request, &response).ok());
    std::vector<std::string> names;
    for (const auto& map : response.maps()) names.push_back(map.name());
    return names;
  };
  EXPECT_THAT(listed(), ElementsAre("lab", "lab-copy"));
  // The copy holds the original's states.
  EXPECT_EQ(Update("lab-copy").update().states_published(), Update("lab").update().states_published());
  Restart();
  EXPECT_THAT(listed(), ElementsAre("lab", "lab-copy"));
}

TEST_F(AdminServiceTest, BadBackupRequests) {
  CreateMap(GenericMap("lab"));
  v1::BackupMapResponse backup;
  for (const char* bad : {"/tmp/x", "../x", "a/../../x", "", "."}) {
    const grpc::Status status = Backup("lab", bad, &backup);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_THAT(status.error_message(), HasSubstr("directory")) << bad;
  }
  EXPECT_EQ(Backup("nowhere", "x", &backup).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Backup("", "x", &backup).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // A directory that holds something already.
  std::filesystem::create_directories(backup_dir() + "/taken");
  dir_.Write("backups/taken/file", "x");
  EXPECT_EQ(Backup("lab", "taken", &backup).error_code(), grpc::StatusCode::ALREADY_EXISTS);
  // An empty one is fine.
  std::filesystem::create_directories(backup_dir() + "/empty");
  EXPECT_TRUE(Backup("lab", "empty", &backup).ok());

  v1::RestoreMapResponse restored;
  const grpc::Status absolute = Restore("copy", "/etc", &restored);
  EXPECT_EQ(absolute.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(absolute.error_message(), HasSubstr("directory"));
  EXPECT_EQ(Restore("copy", "../data", &restored).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

// --- GetServerStatus ---

TEST_F(AdminServiceTest, ServerStatus) {
  CreateMap(GenericMap("lab"));
  WriteStopped("lab", {GenericScan({1, 2, 3}, {0.0f, 1.0f, 1.0f}, kT0), GenericScan({1, 2, 3}, {1.0f, 1.0f, 0.0f}, kT0 + 60)});
  const v1::Operation update = Update("lab");
  v1::GetServerStatusResponse status;
  ASSERT_TRUE(Status(&status).ok());
  EXPECT_EQ(status.version(), "0.1.0");
  const int64_t now = absl::ToUnixSeconds(absl::Now());
  EXPECT_THAT(status.start_time().seconds(), AllOf(Ge(now - 120), Le(now)));
  EXPECT_GE(status.uptime_seconds(), 0);
  EXPECT_EQ(status.map_count(), 1u);
  EXPECT_EQ(status.state_count(), 3u);
  EXPECT_EQ(status.dynamic_state_count(), 2u);  // state 2 was always 1
  EXPECT_EQ(status.running_operations(), 0u);
  EXPECT_EQ(status.update_schedule(), "0 3 * * *");
  EXPECT_EQ(status.update_time_zone(), "UTC");
  // The next 03:00 UTC, within a day.
  const int64_t next = status.next_update_time().seconds();
  EXPECT_THAT(next, AllOf(Ge(now), Le(now + 86400)));
  EXPECT_EQ(next % 86400, 3 * 3600);
  EXPECT_FALSE(status.tls());
  EXPECT_FALSE(status.tokens_required());
  EXPECT_EQ(status.store_state(), v1::STORE_STATE_OPEN);
  EXPECT_GT(status.data_dir_free_bytes(), 0u);
  EXPECT_EQ(status.failed_maps_size(), 0);  // a failing map is covered by MapStoreTest's fault injection
  ASSERT_EQ(status.last_updates_size(), 1);
  EXPECT_EQ(status.last_updates(0).name(), update.name());
  EXPECT_EQ(status.last_updates(0).update().states_published(), 2u);
}

TEST_F(AdminServiceTest, HealthSaysServing) {
  auto health = grpc::health::v1::Health::NewStub(daemon_->NewChannel());
  grpc::health::v1::HealthCheckRequest request;
  request.set_service("fremen.v1.AdminService");
  grpc::health::v1::HealthCheckResponse response;
  ASSERT_TRUE(health->Check(CallContext().get(), request, &response).ok());
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST_F(AdminServiceTest, ServerStatusWithoutSchedule) {
  StopDaemon();
  Start({"--config", dir_.Write("fremend.conf", "update_schedule = \"\"\n")}, /*scheduled=*/false);
  v1::GetServerStatusResponse status;
  ASSERT_TRUE(Status(&status).ok());
  EXPECT_FALSE(status.has_next_update_time());
  EXPECT_EQ(status.update_schedule(), "");
}

// --- tokens ---

class AdminServiceTokenTest : public AdminServiceTest {
 protected:
  void SetUp() override {
    tokens_ = dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n");
    Start({"--tokens-file", tokens_});
  }
  static Metadata Bearer(const std::string& token) { return {{"authorization", "Bearer " + token}}; }
  std::string tokens_;
};

TEST_F(AdminServiceTokenTest, ReadTokenReadsButMayNotWrite) {
  const Metadata reader = Bearer("reader-token"), writer = Bearer("writer-token");
  {
    v1::CreateMapRequest request;
    *request.mutable_map() = GenericMap("lab");
    v1::CreateMapResponse response;
    ASSERT_TRUE(maps_->CreateMap(CallContext(writer).get(), request, &response).ok());
  }
  v1::Operation op;
  const grpc::Status denied = RunUpdate("lab", &op, reader);
  EXPECT_EQ(denied.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(denied.error_message(), HasSubstr("RunUpdate"));
  ASSERT_TRUE(RunUpdate("lab", &op, writer).ok());
  EXPECT_TRUE(GetOperation(op.name(), &op, "", reader).ok());
  EXPECT_EQ(Cancel(op.name(), &op, reader).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(Cancel(op.name(), &op, writer).ok());
  v1::BackupMapResponse backup;
  EXPECT_EQ(Backup("lab", "b", &backup, reader).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  v1::RestoreMapResponse restored;
  EXPECT_EQ(Restore("copy", "b", &restored, reader).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  v1::GetServerStatusResponse status;
  ASSERT_TRUE(Status(&status, reader).ok());
  EXPECT_TRUE(status.tokens_required());
  v1::ListOperationsRequest list;
  v1::ListOperationsResponse listed;
  EXPECT_TRUE(admin_->ListOperations(CallContext(reader).get(), list, &listed).ok());
  EXPECT_EQ(Status(&status).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

// --- order selection (docs/model.md, "Order selection") ---

// A state of true order `order`: a mean plus the first `order` of the daily, 12-hour and 8-hour
// harmonics (all in the default Ω of 24 harmonics of a week), with phases of its own.
struct TrueSignal {
  static constexpr double kPeriods[3] = {kDay, kDay / 2, kDay / 3};
  static constexpr double kAmplitudes[3] = {0.25, 0.15, 0.08};
  int order = 0;
  double phase[3] = {0, 0, 0};
  double operator()(double t) const {
    double p = order == 0 ? 0.3 : 0.5;
    for (int j = 0; j < order; ++j) p += kAmplitudes[j] * std::cos(2 * M_PI * t / kPeriods[j] + phase[j]);
    return p;
  }
};

TEST_F(AdminServiceTest, UpdatesChooseTheTrueOrderOfGeneratedStates) {
  constexpr int kPerOrder = 8;  // states per true order
  constexpr int kMaxTrueOrder = 3;
  v1::Map map = GenericMap("orders");
  map.set_criterion(v1::ERROR_CRITERION_SQUARED);
  CreateMap(map);
  std::mt19937_64 rng(20240331);
  std::uniform_real_distribution<double> phase(0, 2 * M_PI);
  std::normal_distribution<double> noise(0, 0.02);
  std::vector<TrueSignal> signals;
  std::vector<uint64_t> ids;
  for (int order = 0; order <= kMaxTrueOrder; ++order) {
    for (int i = 0; i < kPerOrder; ++i) {
      signals.push_back({order, {phase(rng), phase(rng), phase(rng)}});
      ids.push_back(ids.size() + 1);
    }
  }
  // A week of minute samples, soft observations with Gaussian noise.
  const auto week = [&](int w) {
    std::vector<storage::ObservationBatch> batches;
    for (int minute = 0; minute < 7 * 24 * 60; ++minute) {
      const double t = kT0 + w * 7 * kDay + 60.0 * minute;
      std::vector<float> values;
      for (const TrueSignal& s : signals) values.push_back(static_cast<float>(std::clamp(s(t) + noise(rng), 0.0, 1.0)));
      batches.push_back(GenericScan(ids, values, t));
    }
    return batches;
  };

  // After the first week no order has been scored yet (P did not exist): every state gets order 0.
  WriteStopped("orders", week(0));
  const v1::Operation first = Update("orders");
  ASSERT_EQ(first.error().code(), 0) << first.error().message();
  EXPECT_EQ(first.update().states_published(), ids.size());
  EXPECT_EQ(first.update().order_histogram(0), ids.size());

  // The second week is scored against the P of the first at every order: the update picks each
  // state's true order (more components only fit noise).
  WriteStopped("orders", week(1));
  const v1::Operation second = Update("orders");
  ASSERT_EQ(second.error().code(), 0) << second.error().message();
  EXPECT_LT(second.update().prediction_error_after(), second.update().prediction_error_before());
  EXPECT_THAT(second.update().order_histogram(), ElementsAre(kPerOrder, kPerOrder, kPerOrder, kPerOrder, 0, 0));
  // Each state's model, as clients see it: its true order, made of the true harmonics, strongest first.
  auto query = v1::QueryService::NewStub(daemon_->NewChannel());
  for (size_t i = 0; i < ids.size(); ++i) {
    v1::GetStateModelRequest request;
    request.set_map("orders");
    request.mutable_state()->set_id(ids[i]);
    v1::GetStateModelResponse response;
    const grpc::Status status = query->GetStateModel(CallContext().get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    const v1::StateModel& model = response.model();
    EXPECT_EQ(model.selected_order(), signals[i].order) << "state " << ids[i];
    for (int j = 0; j < signals[i].order && j < model.published_size(); ++j) {
      EXPECT_NEAR(model.published(j).period_seconds(), TrueSignal::kPeriods[j], 1e-6) << "state " << ids[i];
    }
  }
}

// Only states observed since their last update are updated; the job's record shows in the map's
// statistics, and survives a restart.
TEST_F(AdminServiceTest, UpdatesOnlyObservedStatesAndMapStatsKeepTheLastJob) {
  CreateMap(GenericMap("lab"));
  WriteStopped("lab", {GenericScan({1, 2, 3, 4}, {0, 1, 0, 1}, kT0), GenericScan({1, 2, 3, 4}, {1, 0, 1, 0}, kT0 + 60)});
  auto query = v1::QueryService::NewStub(daemon_->NewChannel());
  const auto stats = [&]() {
    v1::GetMapStatsRequest request;
    request.set_map("lab");
    v1::GetMapStatsResponse response;
    const grpc::Status status = query->GetMapStats(CallContext().get(), request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.stats();
  };
  EXPECT_FALSE(stats().has_last_update()) << "no update yet";
  const int64_t now = absl::ToUnixSeconds(absl::Now());
  EXPECT_EQ(Update("lab").update().states_published(), 4u);
  const v1::MapStats after_first = stats();
  ASSERT_TRUE(after_first.has_last_update());
  EXPECT_EQ(after_first.last_update().states_updated(), 4u);
  EXPECT_THAT(after_first.last_update().start_time().seconds(), AllOf(Ge(now - 60), Le(now + 60)));
  EXPECT_GE(after_first.last_update().duration_seconds(), 0);
  EXPECT_THAT(after_first.last_update().order_histogram(), ElementsAre(4u, 0u, 0u, 0u, 0u, 0u));

  EXPECT_EQ(Update("lab").update().states_published(), 0u) << "nothing observed since";
  WriteStopped("lab", {GenericScan({2, 3}, {1, 1}, kT0 + 120)});
  query = v1::QueryService::NewStub(daemon_->NewChannel());
  const v1::Operation third = Update("lab");
  EXPECT_EQ(third.update().states_published(), 2u) << "only states 2 and 3 were observed";
  Restart();
  query = v1::QueryService::NewStub(daemon_->NewChannel());
  const v1::MapStats restarted = stats();
  ASSERT_TRUE(restarted.has_last_update()) << "the record did not survive the restart";
  EXPECT_EQ(restarted.last_update().states_updated(), 2u);
  EXPECT_DOUBLE_EQ(restarted.last_update().prediction_error_after(), third.update().prediction_error_after());
  EXPECT_THAT(restarted.last_update().order_histogram(), ElementsAreArray(third.update().order_histogram()));
  // Server status shows the same record, though the operation itself did not survive the restart.
  v1::GetServerStatusResponse status;
  ASSERT_TRUE(Status(&status).ok());
  EXPECT_EQ(status.last_updates_size(), 0);
  ASSERT_EQ(status.map_updates_size(), 1);
  EXPECT_EQ(status.map_updates(0).map(), "lab");
  EXPECT_EQ(status.map_updates(0).update().states_updated(), 2u);
  EXPECT_THAT(status.map_updates(0).update().order_histogram(), ElementsAreArray(third.update().order_histogram()));
}

// A lossless map's update reconstructs each history, re-transforms it, selects orders on it and
// rebuilds the outlier set, and the past still reconstructs exactly (docs/model.md, "Lossless
// history").
TEST_F(AdminServiceTest, LosslessMapUpdateSelectsOrdersAndReconstructsExactly) {
  constexpr uint32_t kNx = 4, kNy = 2;
  constexpr double kDelta = 600;           // 10-minute slots
  constexpr int kSlots = 4 * 144;          // four days
  v1::Map map = GridMap("hall", kNx, kNy);
  map.set_lossless_sampling_seconds(kDelta);
  map.set_lossless_origin(kT0);
  CreateMap(map);
  // Every cell free at night and occupied by day (a daily square wave), with a few stray slots.
  const auto value = [](int slot) { return ((slot % 144) >= 48 && (slot % 144) < 120) != (slot % 97 == 5); };
  std::vector<storage::ObservationBatch> batches;
  for (int i = 0; i < kSlots; ++i) batches.push_back(GridScan(kNx, kNy, kT0 + kDelta * i, value(i) ? 1.0f : 0.0f));
  WriteStopped("hall", std::move(batches));

  const v1::Operation first = Update("hall");
  ASSERT_EQ(first.error().code(), 0) << first.error().message();
  EXPECT_EQ(first.update().states_published(), kNx * kNy);
  auto query = v1::QueryService::NewStub(daemon_->NewChannel());
  for (uint32_t x = 0; x < kNx; ++x) {
    v1::GetStateModelRequest request;
    request.set_map("hall");
    request.mutable_state()->mutable_cell()->set_x(x);
    request.mutable_state()->mutable_cell()->set_y(1);
    v1::GetStateModelResponse response;
    const grpc::Status status = query->GetStateModel(CallContext().get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    const v1::LosslessModel& lossless = response.model().lossless();
    EXPECT_EQ(lossless.slot_count(), static_cast<uint64_t>(kSlots));
    EXPECT_GT(lossless.selected_order(), 0u) << "a daily square wave needs its daily components";
    ASSERT_GT(lossless.published_size(), 0);
    EXPECT_NEAR(lossless.published(0).period_seconds(), kDay, 1e-6) << "the strongest component is daily";
    EXPECT_GT(lossless.outliers_size(), 0) << "the stray slots are outliers";
    EXPECT_LT(lossless.estimation_error(), 0.1);
  }
  v1::ReconstructRequest request;
  request.set_map("hall");
  *request.mutable_states() = PlaneCells(kNx, kNy);
  request.set_start_time(kT0);
  request.set_end_time(kT0 + kDelta * kSlots);
  v1::ReconstructResponse past;
  const grpc::Status status = query->Reconstruct(CallContext().get(), request, &past);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(past.histories_size(), static_cast<int>(kNx * kNy));
  for (const v1::StateHistory& history : past.histories()) {
    ASSERT_EQ(history.slots().size(), static_cast<size_t>(kSlots));
    for (int i = 0; i < kSlots; ++i) ASSERT_EQ(history.slots()[i], value(i) ? 1 : 0) << "slot " << i;
  }
  EXPECT_EQ(Update("hall").update().states_published(), 0u) << "nothing observed since";
}

}  // namespace
}  // namespace fremen::testing
