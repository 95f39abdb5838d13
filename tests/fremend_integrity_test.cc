// End-to-end: a damaged map file against the real fremend (docs/storage.md, "When the disk misbehaves"). Two maps;
// one's shard file is damaged while the daemon is stopped (a zeroed page, which makes LMDB abort the process that reads
// it, and a flipped bit in a record); at restart the daemon serves the good map, GetServerStatus lists the bad one as
// failed naming its file, calls on it answer DATA_LOSS, and nothing is deleted.
//
// Observations are written with storage::Store in the test process while the daemon is stopped (tests/store_writer.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/map_info.h"
#include "storage/store.h"
#include "storage/testing/file_damage.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"
#include "tests/store_writer.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

constexpr double kT0 = 1'700'006'400;
constexpr uint64_t kStates = 1024;

class FremendIntegrityTest : public DaemonTest {
 protected:
  void Connect() {
    admin_ = v1::AdminService::NewStub(daemon_->NewChannel());
    maps_ = v1::MapService::NewStub(daemon_->NewChannel());
    query_ = v1::QueryService::NewStub(daemon_->NewChannel());
  }
  void CreateGenericMap(const std::string& name) {
    v1::CreateMapRequest request;
    *request.mutable_map() = GenericMapSpec(name);
    request.mutable_map()->set_shards(1);
    v1::CreateMapResponse response;
    const grpc::Status status = maps_->CreateMap(CallContext().get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  // 1024 states, each with its own rhythm, over 24 hourly scans: a shard file of many pages.
  static std::vector<storage::ObservationBatch> Scans() {
    std::vector<uint64_t> ids;
    for (uint64_t k = 1; k <= kStates; ++k) ids.push_back(k);
    std::vector<storage::ObservationBatch> scans;
    for (int i = 0; i < 24; ++i) {
      std::vector<float> values;
      for (uint64_t k = 1; k <= kStates; ++k)
        values.push_back(static_cast<float>(std::fmod(std::sqrt(2.0) * k + 0.1 * i, 1.0)));
      scans.push_back(GenericScan(ids, values, kT0 + 3600.0 * i));
    }
    return scans;
  }
  grpc::Status Predict(const std::string& map, v1::PredictResponse* response) {
    v1::PredictRequest request;
    request.set_map(map);
    for (uint64_t k = 1; k <= kStates; ++k) request.mutable_states()->add_ids(k);
    request.add_times(kT0 + 86400);
    return query_->Predict(CallContext().get(), request, response);
  }
  std::string MapDirOf(const std::string& name) {
    auto store = storage::Store::Open(data_dir(), {});
    EXPECT_TRUE(store.ok()) << store.status();
    if (!store.ok()) return "";
    auto info = (*store)->GetMap(name);
    EXPECT_TRUE(info.ok()) << info.status();
    return info.ok() ? data_dir() + "/maps/" + std::to_string(info->id) : "";
  }

  std::unique_ptr<v1::AdminService::Stub> admin_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::QueryService::Stub> query_;
};

// The dynamic records of a shard, as stored (found in the file by their bytes).
std::vector<std::string> DynamicValues(const std::string& shard_dir) {
  storage::LmdbOptions options;
  options.databases = {"dynamic"};
  auto env = storage::LmdbEnv::Open(shard_dir, options);
  EXPECT_TRUE(env.ok()) << env.status();
  std::vector<std::string> values;
  if (!env.ok()) return values;
  EXPECT_TRUE((*env)
                  ->Read([&](storage::LmdbTxn& txn) {
                    return txn.Scan(*txn.Db("dynamic"), {}, {}, [&](auto, auto value) {
                      values.emplace_back(value.begin(), value.end());
                      return true;
                    });
                  })
                  .ok());
  return values;
}

std::span<const uint8_t> Bytes(const std::string& s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

TEST_F(FremendIntegrityTest, ADamagedShardFailsItsMapAloneAndTheDaemonServesTheOthers) {
  Connect();
  CreateGenericMap("good");
  CreateGenericMap("bad");
  ASSERT_FALSE(HasFatalFailure());
  StopDaemon();
  ASSERT_TRUE(WriteBatches(data_dir(), "good", Scans()).ok());
  ASSERT_TRUE(WriteBatches(data_dir(), "bad", Scans()).ok());
  StartDaemon();
  ASSERT_FALSE(HasFatalFailure());
  Connect();
  v1::PredictResponse before;
  ASSERT_TRUE(Predict("good", &before).ok());
  ASSERT_EQ(before.probabilities_size(), static_cast<int>(kStates));
  StopDaemon();

  // Damage, with the daemon stopped: a zeroed page under a dynamic record of "bad" (every copy of it LMDB left in the
  // file, so that the live one is hit).
  const std::string bad_dir = MapDirOf("bad");
  ASSERT_FALSE(bad_dir.empty());
  const std::string shard_dir = bad_dir + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<std::string> values = DynamicValues(shard_dir);
  ASSERT_EQ(values.size(), kStates);
  const std::vector<size_t> copies =
      storage::testing::FindAll(storage::testing::ReadWholeFile(file), Bytes(values[values.size() / 2]));
  ASSERT_FALSE(copies.empty());
  for (const size_t at : copies) storage::testing::ZeroPage(file, at / 4096);

  // The daemon comes up SERVING (the fixture waits for the health service to say so).
  StartDaemon();
  ASSERT_FALSE(HasFatalFailure());
  Connect();
  grpc::health::v1::HealthCheckResponse health;
  auto health_stub = grpc::health::v1::Health::NewStub(daemon_->NewChannel());
  ASSERT_TRUE(health_stub->Check(CallContext().get(), grpc::health::v1::HealthCheckRequest(), &health).ok());
  EXPECT_EQ(health.status(), grpc::health::v1::HealthCheckResponse::SERVING);

  // The good map serves, unchanged.
  v1::PredictResponse after;
  ASSERT_TRUE(Predict("good", &after).ok());
  EXPECT_EQ(std::vector<float>(after.probabilities().begin(), after.probabilities().end()),
            std::vector<float>(before.probabilities().begin(), before.probabilities().end()));

  // The bad map: failed in the server status, naming the file; DATA_LOSS for calls on its data.
  v1::GetServerStatusResponse status;
  ASSERT_TRUE(admin_->GetServerStatus(CallContext().get(), v1::GetServerStatusRequest(), &status).ok());
  ASSERT_EQ(status.failed_maps_size(), 1);
  EXPECT_EQ(status.failed_maps(0).map(), "bad");
  EXPECT_THAT(status.failed_maps(0).error(), HasSubstr("DATA_LOSS"));
  EXPECT_THAT(status.failed_maps(0).error(), HasSubstr(file + " is damaged: LMDB aborted reading it (signal 6"));
  EXPECT_EQ(status.map_count(), 2u);
  EXPECT_EQ(status.unknown_directories_size(), 0);
  v1::PredictResponse refused;
  const grpc::Status predicted = Predict("bad", &refused);
  EXPECT_EQ(predicted.error_code(), grpc::StatusCode::DATA_LOSS) << predicted.error_message();
  EXPECT_THAT(predicted.error_message(), HasSubstr(file));
  // Still a map of the catalog: GetMap and ListMaps show it.
  v1::GetMapRequest get;
  get.set_map("bad");
  v1::GetMapResponse info;
  EXPECT_TRUE(maps_->GetMap(CallContext().get(), get, &info).ok());
  // The daemon said so in its log, at error.
  EXPECT_THAT(daemon_->Log(), HasSubstr("map bad is failed and not served"));
  // Nothing was removed or repaired: the damaged file is there for an operator.
  EXPECT_TRUE(std::filesystem::exists(file));
}

// A flipped bit in one record of a map: DATA_LOSS naming the file and the record's key, never a model computed from the
// damaged bytes.
TEST_F(FremendIntegrityTest, AFlippedBitInARecordIsDataLossNamingFileAndKey) {
  Connect();
  CreateGenericMap("flipped");
  ASSERT_FALSE(HasFatalFailure());
  StopDaemon();
  ASSERT_TRUE(WriteBatches(data_dir(), "flipped", Scans()).ok());
  const std::string shard_dir = MapDirOf("flipped") + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<std::string> values = DynamicValues(shard_dir);
  ASSERT_EQ(values.size(), kStates);
  const std::vector<size_t> copies =
      storage::testing::FindAll(storage::testing::ReadWholeFile(file), Bytes(values[100]));
  ASSERT_FALSE(copies.empty());
  for (const size_t at : copies) storage::testing::FlipBit(file, at + 40, 3);

  StartDaemon();
  ASSERT_FALSE(HasFatalFailure());
  Connect();
  v1::PredictResponse response;
  const grpc::Status predicted = Predict("flipped", &response);
  EXPECT_EQ(predicted.error_code(), grpc::StatusCode::DATA_LOSS) << predicted.error_message();
  EXPECT_THAT(predicted.error_message(), HasSubstr(file));
  EXPECT_THAT(predicted.error_message(), HasSubstr("database dynamic, key 0000000000000065: checksum mismatch"));
  EXPECT_EQ(response.probabilities_size(), 0);
}

// One flipped bit changes a map's id in catalog/data.mdb. The daemon used to remove that map's directory at the next
// start. Now the record is DATA_LOSS, the map is listed as failed, its directory is reported (unknown_directories) and
// left, and the other map serves.
TEST_F(FremendIntegrityTest, ACatalogBitFlipDeletesNothingAndIsReported) {
  Connect();
  CreateGenericMap("alpha");
  CreateGenericMap("beta");
  ASSERT_FALSE(HasFatalFailure());
  StopDaemon();
  ASSERT_TRUE(WriteBatches(data_dir(), "alpha", Scans()).ok());
  ASSERT_TRUE(WriteBatches(data_dir(), "beta", Scans()).ok());
  storage::MapInfo alpha;
  {
    auto store = storage::Store::Open(data_dir(), {});
    ASSERT_TRUE(store.ok()) << store.status();
    auto info = (*store)->GetMap("alpha");
    ASSERT_TRUE(info.ok()) << info.status();
    alpha = *info;
  }
  const std::string catalog = data_dir() + "/catalog/data.mdb";
  const std::vector<size_t> copies =
      storage::testing::FindAll(storage::testing::ReadWholeFile(catalog), Bytes(storage::EncodeMapInfo(alpha)));
  ASSERT_FALSE(copies.empty());
  // version | name length | "alpha" | id: the id's lowest bit.
  for (const size_t at : copies) storage::testing::FlipBit(catalog, at + 2 + alpha.name.size(), 0);
  const std::string alpha_dir = data_dir() + "/maps/" + std::to_string(alpha.id);

  StartDaemon();
  ASSERT_FALSE(HasFatalFailure());
  Connect();
  v1::PredictResponse response;
  EXPECT_TRUE(Predict("beta", &response).ok());
  const grpc::Status refused = Predict("alpha", &response);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::DATA_LOSS) << refused.error_message();
  EXPECT_THAT(refused.error_message(), HasSubstr(catalog));
  v1::GetServerStatusResponse status;
  ASSERT_TRUE(admin_->GetServerStatus(CallContext().get(), v1::GetServerStatusRequest(), &status).ok());
  ASSERT_EQ(status.failed_maps_size(), 1);
  EXPECT_EQ(status.failed_maps(0).map(), "alpha");
  EXPECT_THAT(status.failed_maps(0).error(), HasSubstr("checksum mismatch"));
  ASSERT_EQ(status.unknown_directories_size(), 1);
  EXPECT_EQ(status.unknown_directories(0), alpha_dir);
  EXPECT_THAT(daemon_->Log(), HasSubstr(alpha_dir + " is not a map of the catalog"));
  // The map's files are all there.
  EXPECT_TRUE(std::filesystem::exists(alpha_dir + "/shard-0/data.mdb"));
}

// The background scrub finds damage that nothing reads: a map is scrubbed clean, then a record's bits flip on disk
// while the daemon serves it (its models are in memory, so queries do not notice), and the next pass reports the record
// in GetServerStatus. Nothing is repaired or removed.
TEST_F(FremendIntegrityTest, TheBackgroundScrubReportsARecordDamagedWhileTheDaemonServes) {
  Connect();
  CreateGenericMap("scrubbed");
  ASSERT_FALSE(HasFatalFailure());
  StopDaemon();
  ASSERT_TRUE(WriteBatches(data_dir(), "scrubbed", Scans()).ok());
  const std::string shard_dir = MapDirOf("scrubbed") + "/shard-0", file = shard_dir + "/data.mdb";
  const std::vector<std::string> values = DynamicValues(shard_dir);
  ASSERT_EQ(values.size(), kStates);

  StartDaemon({"--scrub-interval", "1s"});
  ASSERT_FALSE(HasFatalFailure());
  Connect();
  // Waits (up to a minute: only a broken scrub takes that long) for a scrub of the map that `done` accepts.
  const auto await_scrub = [&](const std::function<bool(const v1::MapScrub&)>& done) -> std::optional<v1::MapScrub> {
    for (const absl::Time deadline = absl::Now() + absl::Minutes(1); absl::Now() < deadline;) {
      v1::GetServerStatusResponse status;
      const grpc::Status answered = admin_->GetServerStatus(CallContext().get(), v1::GetServerStatusRequest(), &status);
      EXPECT_TRUE(answered.ok()) << answered.error_message();
      EXPECT_TRUE(status.has_next_scrub_time());
      for (const v1::MapScrub& scrub : status.map_scrubs()) {
        if (scrub.map() == "scrubbed" && done(scrub)) return scrub;
      }
      absl::SleepFor(absl::Milliseconds(100));
    }
    return std::nullopt;
  };
  const std::optional<v1::MapScrub> first = await_scrub([](const v1::MapScrub&) { return true; });
  ASSERT_TRUE(first.has_value()) << daemon_->Log();
  EXPECT_TRUE(first->clean());
  EXPECT_EQ(first->problem_count(), 0u);
  EXPECT_GE(first->records(), kStates);

  const std::vector<size_t> copies =
      storage::testing::FindAll(storage::testing::ReadWholeFile(file), Bytes(values[100]));
  ASSERT_FALSE(copies.empty());
  for (const size_t at : copies) storage::testing::FlipBit(file, at + 40, 3);
  const std::optional<v1::MapScrub> damaged = await_scrub([](const v1::MapScrub& scrub) { return !scrub.clean(); });
  ASSERT_TRUE(damaged.has_value()) << daemon_->Log();
  // The record, and what follows from its loss: the touched list names a state the shard no longer holds.
  ASSERT_EQ(damaged->problem_count(), 2u) << damaged->DebugString();
  ASSERT_EQ(damaged->problems_size(), 2);
  EXPECT_EQ(damaged->problems(0).file(), "shard-0/data.mdb");
  EXPECT_EQ(damaged->problems(0).location(), "dynamic record #101");
  EXPECT_THAT(damaged->problems(0).description(), HasSubstr("key 0000000000000065: checksum mismatch"));
  EXPECT_EQ(damaged->problems(1).location(), "meta record touched");
  EXPECT_THAT(daemon_->Log(), HasSubstr("scrub of map scrubbed: 2 problems, first shard-0/data.mdb: dynamic record #101"));
  // Still served from memory, and nothing was touched.
  v1::PredictResponse response;
  EXPECT_TRUE(Predict("scrubbed", &response).ok());
  EXPECT_EQ(response.probabilities_size(), static_cast<int>(kStates));
  EXPECT_TRUE(std::filesystem::exists(file));
}

}  // namespace
}  // namespace fremen::testing
