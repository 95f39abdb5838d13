// End-to-end tests of QueryService's predictions against the real fremend: Predict and
// PredictRegion — answers equal to what the store computes for the same states, every output, the
// bad-input rows that apply (each with its exact status code and the field named; requests that
// do not parse), regions larger than one chunk, deadlines and cancellation of huge regions — and
// read-only tokens.
#include <gmock/gmock.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "storage/model/published_model.h"
#include "storage/state_names.h"
#include "tests/query_fixture.h"

namespace fremen::testing {
namespace {

using ::testing::ElementsAreArray;
using ::testing::HasSubstr;

// --- Predict ---

TEST_F(QueryServiceTest, PredictEqualsTheStore) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::PredictRequest request = ProbeRequest();
  v1::PredictResponse response;
  ASSERT_TRUE(Predict(request, &response).ok());
  EXPECT_EQ(response.state_count(), expected_.probe_cells.size());
  EXPECT_EQ(response.time_count(), expected_.times.size());
  EXPECT_THAT(response.probabilities(), ElementsAreArray(expected_.predict));
  EXPECT_TRUE(response.states().empty());
  // (40, 10) and (63, 47) were never observed.
  EXPECT_THAT(response.unobserved(), ElementsAreArray({6u, 7u}));
  EXPECT_EQ(response.probabilities(6), 0.5f);

  request.mutable_options()->set_persistence(true);
  response.Clear();
  ASSERT_TRUE(Predict(request, &response).ok());
  EXPECT_THAT(response.probabilities(), ElementsAreArray(expected_.predict_persistence));

  request.mutable_options()->set_persistence(false);
  request.mutable_options()->set_order(0);
  response.Clear();
  ASSERT_TRUE(Predict(request, &response).ok());
  EXPECT_THAT(response.probabilities(), ElementsAreArray(expected_.predict_order0));
  // The dynamic cells' models are not flat: the override changed something.
  EXPECT_NE(expected_.predict_order0, expected_.predict);
}

TEST_F(QueryServiceTest, PredictByPointEqualsByCell) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::PredictRequest request = ProbeRequest();
  request.mutable_states()->clear_cells();
  for (auto [x, y] : expected_.probe_cells) {
    // Cell centres of a grid at origin (-1, 0) with 0.1 m cells.
    request.mutable_states()->mutable_points()->add_x(-1.0 + 0.1 * x + 0.05);
    request.mutable_states()->mutable_points()->add_y(0.1 * y + 0.05);
  }
  v1::PredictResponse response;
  ASSERT_TRUE(Predict(request, &response).ok());
  EXPECT_THAT(response.probabilities(), ElementsAreArray(expected_.predict));
}

TEST_F(QueryServiceTest, PredictStatesAtConfidence) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::PredictRequest request = ProbeRequest();
  request.set_confidence(0.7f);
  v1::PredictResponse response;
  ASSERT_TRUE(Predict(request, &response).ok());
  ASSERT_EQ(response.states_size(), static_cast<int>(expected_.predict.size()));
  for (size_t i = 0; i < expected_.predict.size(); ++i) {
    EXPECT_EQ(response.states(i), expected_.predict[i] >= 0.7f) << i;
  }
  request.set_states_only(true);
  response.Clear();
  ASSERT_TRUE(Predict(request, &response).ok());
  EXPECT_TRUE(response.probabilities().empty());
  EXPECT_EQ(response.states_size(), static_cast<int>(expected_.predict.size()));
}

TEST_F(QueryServiceTest, PredictGenericStatesByNameAndId) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::PredictRequest request;
  request.set_map("doors");
  request.add_times(kQueryTime);
  for (int i = 0; i < kDoors; ++i) request.mutable_states()->add_names(DoorName(i));
  request.mutable_states()->add_names("never-seen");
  v1::PredictResponse response;
  ASSERT_TRUE(Predict(request, &response).ok());
  std::vector<float> want = expected_.door_p;
  want.push_back(0.5f);
  EXPECT_THAT(response.probabilities(), ElementsAreArray(want));
  EXPECT_THAT(response.unobserved(), ElementsAreArray({static_cast<uint32_t>(kDoors)}));

  request.mutable_states()->clear_names();
  request.mutable_states()->add_ids(storage::StateIdOfName(DoorName(3)));
  response.Clear();
  ASSERT_TRUE(Predict(request, &response).ok());
  EXPECT_THAT(response.probabilities(), ElementsAreArray({expected_.door_p[3]}));
}

TEST_F(QueryServiceTest, PredictBadInput) {
  CreateMap(GridMap("lab", kNx, kNy));
  CreateMap(GridMap("still", 8, 8, /*persistence=*/false));
  CreateMap(GenericMap("doors"));
  const auto base = [] {
    v1::PredictRequest r;
    r.set_map("lab");
    r.mutable_states()->mutable_cells()->add_x(1);
    r.mutable_states()->mutable_cells()->add_y(2);
    r.add_times(kT0);
    return r;
  };
  v1::PredictResponse response;
  v1::PredictRequest r = base();

  r.clear_times();
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "times is empty");
  r = base();
  r.add_times(std::numeric_limits<double>::quiet_NaN());
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "times[1]");
  r = base();
  r.set_times(0, std::numeric_limits<double>::infinity());
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "times[0]");
  r.set_times(0, -2e13);
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "times[0]");
  r.set_times(0, -1);
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "times[0] must be a time in seconds since the Unix epoch");

  r = base();
  r.mutable_options()->set_order(6);  // L = 5
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "options.order");
  r = base();
  r.set_map("still");
  r.mutable_options()->set_persistence(true);
  EXPECT_STATUS(Predict(r, &response), FAILED_PRECONDITION, "options.persistence");

  r = base();
  r.set_confidence(1.5f);
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "confidence");
  r = base();
  r.set_states_only(true);
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "states_only");

  r = base();
  r.mutable_states()->mutable_cells()->add_x(kNx);
  r.mutable_states()->mutable_cells()->add_y(0);
  EXPECT_STATUS(Predict(r, &response), OUT_OF_RANGE, "states.cells[1]");
  r = base();
  r.mutable_states()->mutable_cells()->add_x(3);
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "states.cells.y");
  r = base();
  r.mutable_states()->clear_cells();
  r.mutable_states()->mutable_points()->add_x(-5.0);
  r.mutable_states()->mutable_points()->add_y(0.0);
  EXPECT_STATUS(Predict(r, &response), OUT_OF_RANGE, "states.points[0]");
  r = base();
  r.mutable_states()->clear_cells();
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "states is empty");
  r = base();
  r.mutable_states()->add_ids(7);
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "exactly one of");
  r = base();
  r.mutable_states()->clear_cells();
  r.mutable_states()->add_ids(7);
  EXPECT_STATUS(Predict(r, &response), FAILED_PRECONDITION, "states.ids");
  r.set_map("doors");
  r.mutable_states()->clear_ids();
  r.mutable_states()->add_names("");
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "states.names[0]");

  // 2049 states × 1024 times > 2^21.
  r = base();
  for (int i = 0; i < 2048; ++i) {
    r.mutable_states()->mutable_cells()->add_x(i % kNx);
    r.mutable_states()->mutable_cells()->add_y(0);
  }
  for (int i = 1; i < 1024; ++i) r.add_times(kT0 + i);
  EXPECT_STATUS(Predict(r, &response), RESOURCE_EXHAUSTED, "2049 × 1024");

  r = base();
  r.set_map("nowhere");
  EXPECT_STATUS(Predict(r, &response), NOT_FOUND, "nowhere");
  r.clear_map();
  EXPECT_STATUS(Predict(r, &response), INVALID_ARGUMENT, "map is required");
  r.set_map("lab");
  EXPECT_STATUS(Predict(r, &response, {{"x-fremen-map", "still"}}), INVALID_ARGUMENT, "x-fremen-map");
  // The header alone names the map.
  r.clear_map();
  EXPECT_TRUE(Predict(r, &response, {{"x-fremen-map", "lab"}}).ok());
}

// --- PredictRegion ---

TEST_F(QueryServiceTest, RegionEqualsTheStoreInEveryOutput) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  const std::vector<float>& p = expected_.region;
  const uint64_t cells = uint64_t{kNx} * kNy;

  RegionResult result = Region(WholeLab(v1::REGION_OUTPUT_UNSPECIFIED));
  ASSERT_TRUE(result.status.ok()) << result.status.error_message();
  EXPECT_EQ(Assemble<float>(result, cells), p);

  result = Region(WholeLab(v1::REGION_OUTPUT_UINT8));
  ASSERT_TRUE(result.status.ok());
  const std::vector<char> bytes = Assemble<char>(result, cells);
  for (size_t i = 0; i < cells; ++i) {
    ASSERT_EQ(static_cast<uint8_t>(bytes[i]), static_cast<uint8_t>(std::lround(p[i] * 255.0))) << i;
  }

  result = Region(WholeLab(v1::REGION_OUTPUT_ENTROPY));
  ASSERT_TRUE(result.status.ok());
  const std::vector<float> entropy = Assemble<float>(result, cells);
  for (size_t i = 0; i < cells; ++i) ASSERT_FLOAT_EQ(entropy[i], model::Entropy(p[i])) << i;

  v1::PredictRegionRequest states = WholeLab(v1::REGION_OUTPUT_STATES);
  states.set_confidence(0.6f);
  result = Region(states);
  ASSERT_TRUE(result.status.ok());
  const std::vector<char> s = Assemble<char>(result, cells);
  for (size_t i = 0; i < cells; ++i) ASSERT_EQ(s[i], p[i] >= 0.6f ? 1 : 0) << i;
}

// A region and Predict of the same cells agree; a sub-box is the matching part of the whole.
TEST_F(QueryServiceTest, RegionAgreesWithPredict) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::PredictRegionRequest request = WholeLab(v1::REGION_OUTPUT_FLOAT);
  *request.mutable_lo() = Cell(3, 5);
  *request.mutable_hi() = Cell(37, 9);
  request.set_chunk_cells(7);  // many chunks, of parts of rows
  const RegionResult result = Region(request);
  ASSERT_TRUE(result.status.ok()) << result.status.error_message();
  EXPECT_EQ(result.chunks.size(), 4u * 5);  // 34 cells a row: 5 chunks of ≤ 7
  const std::vector<float> region = Assemble<float>(result, 34 * 4);

  v1::PredictRequest predict;
  predict.set_map("lab");
  predict.add_times(kQueryTime);
  for (uint32_t y = 5; y < 9; ++y) {
    for (uint32_t x = 3; x < 37; ++x) {
      predict.mutable_states()->mutable_cells()->add_x(x);
      predict.mutable_states()->mutable_cells()->add_y(y);
    }
  }
  v1::PredictResponse response;
  ASSERT_TRUE(Predict(predict, &response).ok());
  EXPECT_THAT(response.probabilities(), ElementsAreArray(region));
  for (uint32_t y = 5; y < 9; ++y) {
    for (uint32_t x = 3; x < 37; ++x) {
      ASSERT_EQ(region[(y - 5) * 34 + (x - 3)], expected_.region[y * kNx + x]);
    }
  }
}

// A box of several blocks (the daemon computes up to 1M cells at a time) and many chunks: every
// cell lands at its place. One scan marks scattered cells occupied, the rest free; a corner stays
// unobserved.
TEST_F(QueryServiceTest, LargeRegionIsStreamedInChunks) {
  constexpr uint32_t kSide = 1500;
  constexpr uint64_t kCells = uint64_t{kSide} * kSide;
  const auto occupied = [](uint64_t x, uint64_t y) { return (x * 7 + y * 13) % 101 == 0; };
  CreateMap(GridMap("big", kSide, kSide));
  WithStore([&](storage::Store& store) {
    storage::ObservationBatch scan;
    scan.writer_id = 1;
    scan.sequence = 1;
    scan.time = kT0;
    scan.patch.size = {kSide, kSide - 10, 1};
    for (uint64_t y = 0; y < kSide - 10; ++y) {
      for (uint64_t x = 0; x < kSide; ++x) scan.patch.values.push_back(occupied(x, y) ? 1.0f : 0.0f);
    }
    ASSERT_TRUE((*store.Map("big"))->Write(std::move(scan)).ok());
  });
  ASSERT_FALSE(HasFatalFailure());
  v1::PredictRegionRequest request;
  request.set_map("big");
  *request.mutable_hi() = Cell(kSide, kSide);
  request.set_time(kT0 + 60);
  RegionResult result = Region(request);
  ASSERT_TRUE(result.status.ok()) << result.status.error_message();
  EXPECT_GE(result.chunks.size(), 9u);  // 1 MiB of floats a chunk at most
  for (const auto& chunk : result.chunks) EXPECT_LE(chunk.float_values_size() * 4, 1 << 20);
  const std::vector<float> values = Assemble<float>(result, kCells);
  for (uint64_t i = 0; i < values.size(); ++i) {
    const uint64_t x = i % kSide, y = i / kSide;
    ASSERT_EQ(values[i], y >= kSide - 10 ? 0.5f : occupied(x, y) ? 1.0f : 0.0f) << "cell " << x << ", " << y;
  }

  request.set_output(v1::REGION_OUTPUT_UINT8);
  result = Region(request);
  ASSERT_TRUE(result.status.ok());
  EXPECT_GE(result.chunks.size(), 3u);  // at least one a block
  const std::vector<char> bytes = Assemble<char>(result, kCells);
  for (uint64_t i = 0; i < bytes.size(); ++i) {
    ASSERT_EQ(static_cast<uint8_t>(bytes[i]), static_cast<uint8_t>(std::lround(values[i] * 255))) << i;
  }
}

TEST_F(QueryServiceTest, HugeRegionStopsAtTheDeadline) {
  CreateMap(GridMap("huge", 2097152, 2097152));  // 4.4e12 cells
  v1::PredictRegionRequest request;
  request.set_map("huge");
  *request.mutable_hi() = Cell(2097152, 2097152);
  request.set_time(kT0);
  request.set_output(v1::REGION_OUTPUT_UINT8);
  const auto start = std::chrono::steady_clock::now();
  const RegionResult result = Region(request, std::chrono::milliseconds(300));
  EXPECT_EQ(result.status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << result.status.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  // The daemon stops the stream, logs it, and keeps serving.
  const auto logged = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (daemon_->Log().find("PredictRegion") == std::string::npos && std::chrono::steady_clock::now() < logged) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_THAT(daemon_->Log(), ::testing::ContainsRegex("PredictRegion .* (DEADLINE_EXCEEDED|CANCELLED)"));
  v1::PredictRegionRequest small = request;
  *small.mutable_hi() = Cell(10, 10);
  EXPECT_TRUE(Region(small).status.ok());
}

TEST_F(QueryServiceTest, RegionCancelledByTheClient) {
  CreateMap(GridMap("huge", 2097152, 2097152));
  v1::PredictRegionRequest request;
  request.set_map("huge");
  *request.mutable_hi() = Cell(2097152, 2097152);
  request.set_time(kT0);
  auto context = CallContext();
  auto reader = query_->PredictRegion(context.get(), request);
  v1::PredictRegionResponse chunk;
  ASSERT_TRUE(reader->Read(&chunk));
  EXPECT_EQ(chunk.offset(), 0u);
  EXPECT_EQ(chunk.box_cells(), uint64_t{2097152} * 2097152);
  context->TryCancel();
  while (reader->Read(&chunk)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
}

TEST_F(QueryServiceTest, RegionBadInput) {
  CreateMap(GridMap("lab", kNx, kNy));
  CreateMap(GenericMap("doors"));
  const auto base = [] {
    v1::PredictRegionRequest r;
    r.set_map("lab");
    *r.mutable_hi() = Cell(kNx, kNy);
    r.set_time(kT0);
    return r;
  };
  v1::PredictRegionRequest r = base();
  r.mutable_hi()->set_x(kNx + 1);
  EXPECT_STATUS(Region(r).status, OUT_OF_RANGE, "hi.x");
  r = base();
  r.mutable_lo()->set_y(kNy);
  EXPECT_STATUS(Region(r).status, OUT_OF_RANGE, "hi.y");
  r = base();
  r.mutable_lo()->set_x(5);
  r.mutable_hi()->set_x(5);
  EXPECT_STATUS(Region(r).status, OUT_OF_RANGE, "lo.x");
  r = base();
  r.mutable_hi()->set_z(2);
  EXPECT_STATUS(Region(r).status, OUT_OF_RANGE, "hi.z");
  r = base();
  r.set_map("doors");
  EXPECT_STATUS(Region(r).status, FAILED_PRECONDITION, "not a grid");
  r = base();
  r.set_time(std::numeric_limits<double>::quiet_NaN());
  EXPECT_STATUS(Region(r).status, INVALID_ARGUMENT, "time");
  r = base();
  r.set_output(v1::REGION_OUTPUT_STATES);
  r.set_confidence(-0.5f);
  EXPECT_STATUS(Region(r).status, INVALID_ARGUMENT, "confidence");
  r = base();
  r.set_output(static_cast<v1::RegionOutput>(9));
  EXPECT_STATUS(Region(r).status, INVALID_ARGUMENT, "output");
  r = base();
  r.mutable_options()->set_order(9);
  EXPECT_STATUS(Region(r).status, INVALID_ARGUMENT, "options.order");
  r = base();
  r.set_map("nowhere");
  EXPECT_STATUS(Region(r).status, NOT_FOUND, "nowhere");
}

// The region methods parse their own requests (they are raw, to write their values in place): a
// request that is not the message gets INVALID_ARGUMENT naming it, and the daemon serves on.
grpc::Status CallWithBytes(grpc::Channel& channel, const std::string& method, const std::string& request) {
  grpc::GenericStub stub(channel.shared_from_this());
  grpc::CompletionQueue queue;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  const auto call = stub.PrepareCall(&context, method, &queue);
  const auto step = [&queue](int tag) {
    void* got = nullptr;
    bool ok = false;
    EXPECT_TRUE(queue.Next(&got, &ok));
    EXPECT_EQ(got, reinterpret_cast<void*>(static_cast<intptr_t>(tag)));
    return ok;
  };
  const auto tag = [](int t) { return reinterpret_cast<void*>(static_cast<intptr_t>(t)); };
  call->StartCall(tag(1));
  step(1);
  grpc::Slice slice(request);
  call->WriteLast(grpc::ByteBuffer(&slice, 1), grpc::WriteOptions(), tag(2));
  step(2);
  grpc::ByteBuffer response;
  call->Read(&response, tag(3));
  EXPECT_FALSE(step(3)) << method << " answered a request that does not parse";
  grpc::Status status;
  call->Finish(&status, tag(4));
  step(4);
  queue.Shutdown();
  return status;
}

TEST_F(QueryServiceTest, RegionRequestsThatDoNotParse) {
  CreateMap(GridMap("lab", kNx, kNy));
  const std::string truncated("\x0a\x05la", 4);  // field 1 (map): 5 bytes promised, 2 sent
  const std::shared_ptr<grpc::Channel> channel = daemon_->NewChannel();
  EXPECT_STATUS(CallWithBytes(*channel, "/fremen.v1.QueryService/PredictRegion", truncated), INVALID_ARGUMENT,
                "fremen.v1.PredictRegionRequest");
  EXPECT_STATUS(CallWithBytes(*channel, "/fremen.v1.QueryService/PredictRegionSeries", "\xff"), INVALID_ARGUMENT,
                "fremen.v1.PredictRegionSeriesRequest");
  // And a request that parses is answered.
  v1::PredictRegionRequest whole;
  whole.set_map("lab");
  *whole.mutable_hi() = Cell(kNx, kNy);
  whole.set_time(kT0);
  const RegionResult region = Region(whole);
  EXPECT_TRUE(region.status.ok()) << region.status.error_message();
  EXPECT_EQ(Assemble<float>(region, kNx * kNy).size(), kNx * kNy);
}

// --- Authorization ---

TEST_F(QueryServiceTest, ReadTokenQueriesAndNoTokenIsRefused) {
  const std::string tokens = dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n");
  StopDaemon();
  StartDaemon({"--tokens-file", tokens});
  Connect();
  const Metadata writer = {{"authorization", "Bearer writer-token"}};
  const Metadata reader = {{"authorization", "Bearer reader-token"}};
  CreateAndFillMaps({"--tokens-file", tokens}, writer);
  ASSERT_FALSE(HasFatalFailure());

  v1::PredictResponse predicted;
  ASSERT_TRUE(Predict(ProbeRequest(), &predicted, reader).ok());
  EXPECT_THAT(predicted.probabilities(), ElementsAreArray(expected_.predict));
  EXPECT_TRUE(Predict(ProbeRequest(), &predicted, writer).ok());
  EXPECT_STATUS(Predict(ProbeRequest(), &predicted), UNAUTHENTICATED, "");
  EXPECT_STATUS(Predict(ProbeRequest(), &predicted, {{"authorization", "Bearer wrong"}}), UNAUTHENTICATED, "");

  EXPECT_TRUE(Region(WholeLab(v1::REGION_OUTPUT_FLOAT), std::chrono::seconds(30), reader).status.ok());
  EXPECT_STATUS(Region(WholeLab(v1::REGION_OUTPUT_FLOAT)).status, UNAUTHENTICATED, "");

  v1::GetMapStatsRequest stats;
  stats.set_map("lab");
  v1::GetMapStatsResponse stats_response;
  EXPECT_TRUE(query_->GetMapStats(CallContext(reader).get(), stats, &stats_response).ok());
  v1::GetStateModelRequest model;
  model.set_map("lab");
  *model.mutable_state()->mutable_cell() = Cell(4, 7);
  v1::GetStateModelResponse model_response;
  EXPECT_TRUE(query_->GetStateModel(CallContext(reader).get(), model, &model_response).ok());
}

}  // namespace
}  // namespace fremen::testing
