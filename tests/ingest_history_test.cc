// End-to-end tests of histories (IngestRequest.history: a time per observation) against the real
// fremend: a map fed histories and a map fed the same observations one scan per time end with
// bit-identical models, statistics and predictions, before and after the update job and after a
// kill -9 (the log replays a history exactly); a retried history is a duplicate as a whole; bad
// histories are refused naming the field while the stream goes on; a history without values labels
// its state.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

struct Observation {
  double time;
  uint64_t id;
  float value;
};

// Three doors a minute apart for two days, one to three of them seen at each time, a stretch
// uploaded late (its times go back), and one value outside [0, 1].
std::vector<Observation> DoorLog() {
  std::mt19937 rng(15);
  std::vector<Observation> log;
  for (int minute = 0; minute < 2 * 1440; ++minute) {
    const int late = minute >= 2000 && minute < 2100 ? -1500 : 0;
    const double t = 1.7e9 + 60.0 * (minute + late);
    const double day = std::fmod(t, 86400.0) / 86400.0;
    for (uint64_t id : {11u, 22u, 33u}) {
      if (rng() % 3 == 0) continue;
      const bool open = std::sin(2 * M_PI * day + static_cast<double>(id)) > 0.2 || rng() % 10 == 0;
      log.push_back({t, id, open ? 1.0f : (rng() % 4 == 0 ? 0.3f : 0.0f)});
    }
  }
  log[500].value = 1.5f;
  return log;
}

v1::IngestRequest Request(const std::string& map, uint64_t sequence) {
  v1::IngestRequest request;
  request.set_map(map);
  request.set_writer_id(5);
  request.set_sequence(sequence);
  return request;
}

// The log as histories of at most `per_batch` observations.
std::vector<v1::IngestRequest> Histories(const std::string& map, const std::vector<Observation>& log, size_t per_batch) {
  std::vector<v1::IngestRequest> batches;
  for (size_t i = 0; i < log.size(); ++i) {
    if (i % per_batch == 0) batches.push_back(Request(map, batches.size() + 1));
    v1::HistoryObservations* h = batches.back().mutable_history();
    h->add_times(log[i].time);
    h->add_ids(log[i].id);
    h->add_values(log[i].value);
  }
  return batches;
}

// The log as one scan per run of observations with the same time.
std::vector<v1::IngestRequest> Scans(const std::string& map, const std::vector<Observation>& log) {
  std::vector<v1::IngestRequest> batches;
  for (size_t i = 0; i < log.size(); ++i) {
    if (i == 0 || log[i].time != log[i - 1].time) {
      batches.push_back(Request(map, batches.size() + 1));
      batches.back().set_time(log[i].time);
    }
    batches.back().mutable_states()->add_ids(log[i].id);
    batches.back().mutable_states()->add_values(log[i].value);
  }
  return batches;
}

class IngestHistoryTest : public DaemonTest {
 protected:
  void SetUp() override {
    DaemonTest::SetUp();
    if (!HasFatalFailure()) Connect();
  }
  void Connect() {
    channel_ = daemon_->NewChannel();
    maps_ = v1::MapService::NewStub(channel_);
    ingest_ = v1::IngestService::NewStub(channel_);
    query_ = v1::QueryService::NewStub(channel_);
    admin_ = v1::AdminService::NewStub(channel_);
  }
  void Create(const std::string& name) {
    v1::CreateMapRequest request;
    *request.mutable_map() = GenericMapSpec(name);
    request.mutable_map()->set_shards(2);  // a history's runs split across shards
    v1::CreateMapResponse response;
    const grpc::Status status = maps_->CreateMap(CallContext().get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  // Sends every batch on one stream, then reads every answer.
  std::vector<v1::IngestResponse> Send(const std::vector<v1::IngestRequest>& batches) {
    auto context = CallContext({}, std::chrono::seconds(120));
    auto stream = ingest_->Ingest(context.get());
    std::vector<v1::IngestResponse> responses;
    std::thread reader([&] {
      v1::IngestResponse response;
      while (stream->Read(&response)) responses.push_back(response);
    });
    for (const v1::IngestRequest& b : batches) EXPECT_TRUE(stream->Write(b));
    stream->WritesDone();
    reader.join();
    const grpc::Status status = stream->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(responses.size(), batches.size());
    return responses;
  }
  // Everything the map answers about the doors, as bytes: each state's model with its spectrum,
  // predictions at times across a week, and the statistics that do not depend on the bytes stored.
  std::string Answers(const std::string& map) {
    std::string out;
    for (uint64_t id : {11u, 22u, 33u, 44u}) {
      v1::GetStateModelRequest request;
      request.set_map(map);
      request.mutable_state()->set_id(id);
      request.set_include_spectrum(true);
      v1::GetStateModelResponse response;
      const grpc::Status status = query_->GetStateModel(CallContext().get(), request, &response);
      EXPECT_TRUE(status.ok()) << status.error_message();
      out += response.SerializeAsString();
    }
    v1::PredictRequest predict;
    predict.set_map(map);
    for (uint64_t id : {11u, 22u, 33u, 44u}) predict.mutable_states()->add_ids(id);
    for (int h = 0; h < 7 * 24; h += 5) predict.add_times(1.7e9 + 3600.0 * h + 17);
    v1::PredictResponse predicted;
    const grpc::Status status = query_->Predict(CallContext().get(), predict, &predicted);
    EXPECT_TRUE(status.ok()) << status.error_message();
    out += predicted.SerializeAsString();
    v1::GetMapStatsRequest stats_request;
    stats_request.set_map(map);
    v1::GetMapStatsResponse stats;
    EXPECT_TRUE(query_->GetMapStats(CallContext().get(), stats_request, &stats).ok());
    v1::MapStats kept;
    kept.set_states(stats.stats().states());
    kept.set_dynamic_states(stats.stats().dynamic_states());
    kept.set_observations(stats.stats().observations());
    *kept.mutable_order_histogram() = stats.stats().order_histogram();
    kept.set_mean_prediction_error(stats.stats().mean_prediction_error());
    kept.set_compression_ratio(stats.stats().compression_ratio());
    out += kept.SerializeAsString();
    return out;
  }
  void Update(const std::string& map) {
    v1::RunUpdateRequest request;
    request.set_map(map);
    v1::Operation op;
    ASSERT_TRUE(admin_->RunUpdate(CallContext().get(), request, &op).ok());
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
    while (!op.done() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling a real daemon
      v1::GetOperationRequest get;
      get.set_map(map);
      get.set_name(op.name());
      ASSERT_TRUE(admin_->GetOperation(CallContext().get(), get, &op).ok());
    }
    ASSERT_TRUE(op.done()) << op.name() << " not done after 2 minutes";
  }
  // Feeds the door log to map `by_history` as histories (and door 44's own history with a single
  // id) and to `by_scans` one scan per time.
  void FeedBoth(const std::string& by_history, const std::string& by_scans) {
    const std::vector<Observation> log = DoorLog();
    uint64_t accepted = 0, rejected = 0;
    std::vector<v1::IngestRequest> histories = Histories(by_history, log, 1000);
    v1::IngestRequest door = Request(by_history, histories.size() + 1);
    std::vector<Observation> door_log;
    for (int minute = 0; minute < 1440; ++minute) {
      door_log.push_back({1.7e9 + 60.0 * minute, 44, minute % 480 < 200 ? 1.0f : 0.0f});
      door.mutable_history()->add_times(door_log.back().time);
      door.mutable_history()->add_values(door_log.back().value);
    }
    door.mutable_history()->add_ids(44);
    histories.push_back(door);
    for (const v1::IngestResponse& r : Send(histories)) {
      EXPECT_FALSE(r.has_error()) << r.error().message();
      accepted += r.accepted();
      rejected += r.rejected();
    }
    EXPECT_EQ(accepted + rejected, log.size() + door_log.size());
    EXPECT_EQ(rejected, 1u);
    std::vector<v1::IngestRequest> scans = Scans(by_scans, log);
    for (v1::IngestRequest& scan : Scans(by_scans, door_log)) {
      scan.set_sequence(scans.size() + 1);
      scans.push_back(std::move(scan));
    }
    uint64_t scan_accepted = 0;
    for (const v1::IngestResponse& r : Send(scans)) scan_accepted += r.accepted();
    EXPECT_EQ(scan_accepted, accepted);
  }

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::IngestService::Stub> ingest_;
  std::unique_ptr<v1::QueryService::Stub> query_;
  std::unique_ptr<v1::AdminService::Stub> admin_;
};

TEST_F(IngestHistoryTest, AHistoryGivesTheModelsOfOneScanPerTimeBitForBit) {
  Create("by_history");
  Create("by_scans");
  FeedBoth("by_history", "by_scans");
  const std::string before = Answers("by_history");
  EXPECT_EQ(before, Answers("by_scans"));
  Update("by_history");
  Update("by_scans");
  const std::string after = Answers("by_history");
  EXPECT_NE(after, before) << "the update job published nothing: the comparison would be weak";
  EXPECT_EQ(after, Answers("by_scans"));
}

TEST_F(IngestHistoryTest, KillMinus9ReplaysAHistoryFromTheLogExactly) {
  Create("by_history");
  Create("by_scans");
  FeedBoth("by_history", "by_scans");
  const std::string acknowledged = Answers("by_history");
  daemon_->Kill();
  daemon_.reset();
  StartDaemon();
  Connect();
  EXPECT_EQ(Answers("by_history"), acknowledged);
  EXPECT_EQ(Answers("by_history"), Answers("by_scans"));
}

TEST_F(IngestHistoryTest, ARetriedHistoryIsADuplicateAsAWholeAndReusingItsSequenceIsRefused) {
  Create("doors");
  const std::vector<v1::IngestRequest> batches = Histories("doors", DoorLog(), 2000);
  const std::vector<v1::IngestResponse> first = Send({batches[0]});
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].accepted(), 1999u);
  const std::string applied = Answers("doors");
  const std::vector<v1::IngestResponse> again = Send({batches[0]});
  ASSERT_EQ(again.size(), 1u);
  EXPECT_TRUE(again[0].duplicate());
  EXPECT_EQ(again[0].accepted(), 0u);
  EXPECT_EQ(Answers("doors"), applied);
  v1::IngestRequest changed = batches[0];
  changed.mutable_history()->set_times(7, changed.history().times(7) + 1);
  const std::vector<v1::IngestResponse> reused = Send({changed});
  ASSERT_EQ(reused.size(), 1u);
  EXPECT_EQ(reused[0].error().code(), static_cast<int>(grpc::StatusCode::ALREADY_EXISTS));
  EXPECT_EQ(Answers("doors"), applied);
}

TEST_F(IngestHistoryTest, BadHistoriesAreRefusedNamingTheFieldAndTheStreamGoesOn) {
  Create("doors");
  v1::CreateMapRequest grid;
  *grid.mutable_map() = GridMapSpec("lab", 10, 10, 0.5);
  v1::CreateMapResponse created;
  ASSERT_TRUE(maps_->CreateMap(CallContext().get(), grid, &created).ok());
  const auto history = [](const std::string& map, uint64_t sequence) {
    v1::IngestRequest r = Request(map, sequence);
    for (int i = 0; i < 4; ++i) {
      r.mutable_history()->add_times(1.7e9 + i);
      r.mutable_history()->add_values(1.0f);
    }
    r.mutable_history()->add_ids(1);
    return r;
  };
  struct Case {
    v1::IngestRequest request;
    std::string field;
  };
  std::vector<Case> cases;
  cases.push_back({history("doors", 1), "history.times[2]"});
  cases.back().request.mutable_history()->set_times(2, NAN);
  cases.push_back({history("doors", 2), "history.times[3]"});
  cases.back().request.mutable_history()->set_times(3, 2e13);
  cases.push_back({history("doors", 3), "history.times[0]"});
  cases.back().request.mutable_history()->set_times(0, -1);
  cases.push_back({history("doors", 4), "history.times has 3 times for 4 values"});
  cases.back().request.mutable_history()->mutable_times()->RemoveLast();
  cases.push_back({history("doors", 5), "history.ids has 2 ids for 4 values"});
  cases.back().request.mutable_history()->add_ids(2);
  cases.push_back({history("doors", 6), "time must be 0 (unset) with history"});
  cases.back().request.set_time(1.7e9);
  cases.push_back({history("doors", 7), "history.names has 2 names for 1 ids"});
  cases.back().request.mutable_history()->add_names("a");
  cases.back().request.mutable_history()->add_names("b");
  std::vector<v1::IngestRequest> requests;
  for (const Case& c : cases) requests.push_back(c.request);
  requests.push_back(history("doors", 8));  // a good one after them: the stream went on
  const std::vector<v1::IngestResponse> responses = Send(requests);
  ASSERT_EQ(responses.size(), requests.size());
  for (size_t i = 0; i < cases.size(); ++i) {
    EXPECT_EQ(responses[i].error().code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT)) << cases[i].field;
    EXPECT_THAT(responses[i].error().message(), HasSubstr(cases[i].field));
    EXPECT_EQ(responses[i].accepted(), 0u);
  }
  EXPECT_FALSE(responses.back().has_error()) << responses.back().error().message();
  EXPECT_EQ(responses.back().accepted(), 4u);
  const std::vector<v1::IngestResponse> on_grid = Send({history("lab", 1)});
  ASSERT_EQ(on_grid.size(), 1u);
  EXPECT_EQ(on_grid[0].error().code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(on_grid[0].error().message(), HasSubstr("history observations are only for generic maps"));
}

// A history of one state without values only labels the state. The daemon once read the label's
// key from the (empty) observations and died of it: now the state is listed and the stream goes on.
TEST_F(IngestHistoryTest, AOneStateHistoryWithoutValuesLabelsItsStateAndTheStreamGoesOn) {
  Create("doors");
  v1::IngestRequest empty = Request("doors", 1);
  empty.mutable_history()->add_ids(77);
  empty.mutable_history()->add_names("cellar door");
  empty.mutable_history()->add_groups("doors");
  v1::IngestRequest next = Request("doors", 2);
  next.mutable_history()->add_times(1.7e9);
  next.mutable_history()->add_values(1.0f);
  next.mutable_history()->add_ids(77);
  const std::vector<v1::IngestResponse> responses = Send({empty, next});
  ASSERT_EQ(responses.size(), 2u);
  EXPECT_FALSE(responses[0].has_error()) << responses[0].error().message();
  EXPECT_EQ(responses[0].accepted(), 0u);
  EXPECT_FALSE(responses[1].has_error()) << responses[1].error().message();
  EXPECT_EQ(responses[1].accepted(), 1u);
  v1::ListStatesRequest list;
  list.set_map("doors");
  v1::ListStatesResponse listed;
  ASSERT_TRUE(query_->ListStates(CallContext().get(), list, &listed).ok());
  ASSERT_EQ(listed.states_size(), 1);
  EXPECT_EQ(listed.states(0).id(), 77u);
  EXPECT_EQ(listed.states(0).name(), "cellar door");
  EXPECT_EQ(listed.states(0).group(), "doors");
}

}  // namespace
}  // namespace fremen::testing
