// End-to-end tests of fremen.v1.IngestService against the real fremend: scans of every kind and
// their acknowledgements, retries recognised as duplicates, every bad-input row that applies to
// ingest (each with its exact status code and the field named), token roles, SIGTERM draining a
// stream, data surviving a restart, and kill -9 during ingest from three clients losing no
// acknowledged batch. The contract with writers (a batch is a duplicate only if it is the same
// batch; LastSequence) and with streams that carry an unparsable message.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "absl/strings/str_cat.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;
using Metadata = std::vector<std::pair<std::string, std::string>>;
using Cell = std::array<uint32_t, 3>;

constexpr double kTime = 1.7e9;
// How many of a writer's highest sequences the daemon recognises retries among (ingest.proto).
constexpr uint64_t kWriterWindow = 256;

// A grid of 40×30×4 cells of 0.5 m from (0, 0, 0).
v1::Map GridMap(const std::string& name) {
  v1::Map map = GridMapSpec(name, 40, 30, 0.5);
  map.mutable_grid()->mutable_size()->set_z(4);
  map.set_shards(2);
  return map;
}

v1::Map GenericMap(const std::string& name) {
  v1::Map map = GenericMapSpec(name);
  map.set_shards(2);
  return map;
}

v1::IngestRequest Batch(const std::string& map, uint64_t writer, uint64_t sequence, double time = kTime) {
  v1::IngestRequest request;
  request.set_map(map);
  request.set_writer_id(writer);
  request.set_sequence(sequence);
  request.set_time(time);
  return request;
}

v1::IngestRequest CellBatch(const std::string& map, uint64_t writer, uint64_t sequence,
                            const std::vector<Cell>& cells, const std::vector<float>& values) {
  v1::IngestRequest request = Batch(map, writer, sequence);
  v1::CellIndices* indices = request.mutable_cells()->mutable_cells();
  for (const Cell& c : cells) {
    indices->add_x(c[0]);
    indices->add_y(c[1]);
    indices->add_z(c[2]);
  }
  for (float v : values) request.mutable_cells()->add_values(v);
  return request;
}

// n cells of a row, all occupied.
v1::IngestRequest RowBatch(const std::string& map, uint64_t writer, uint64_t sequence, uint32_t n = 40) {
  std::vector<Cell> cells;
  for (uint32_t x = 0; x < n; ++x) cells.push_back({x % 40, static_cast<uint32_t>(sequence % 30), 0});
  return CellBatch(map, writer, sequence, cells, std::vector<float>(n, 1.0f));
}

// One Ingest call, driven synchronously.
class Stream {
 public:
  explicit Stream(v1::IngestService::Stub& stub, const Metadata& metadata = {})
      : context_(CallContext(metadata, std::chrono::seconds(120))), stream_(stub.Ingest(context_.get())) {}

  bool Send(const v1::IngestRequest& request) { return stream_->Write(request); }
  std::optional<v1::IngestResponse> Receive() {
    v1::IngestResponse response;
    if (!stream_->Read(&response)) return std::nullopt;
    return response;
  }
  // Sends one batch and waits for its response.
  v1::IngestResponse Call(const v1::IngestRequest& request) {
    EXPECT_TRUE(Send(request));
    auto response = Receive();
    EXPECT_TRUE(response.has_value()) << "the stream ended: " << Finish().error_message();
    return response.value_or(v1::IngestResponse());
  }
  // Closes the client's side, reads what is left and returns the call's status.
  grpc::Status Close() {
    stream_->WritesDone();
    return Finish();
  }
  grpc::Status Finish() {
    v1::IngestResponse ignored;
    while (stream_->Read(&ignored)) {}
    return stream_->Finish();
  }
  grpc::ClientContext& context() { return *context_; }

 private:
  std::unique_ptr<grpc::ClientContext> context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::IngestRequest, v1::IngestResponse>> stream_;
};

// One Ingest call whose messages are bytes, so that a test can send what no protobuf library would
// (made as the generated stub makes its streams, with ByteBuffer for both message types).
class RawStream {
 public:
  explicit RawStream(grpc::Channel& channel)
      : context_(CallContext({}, std::chrono::seconds(120))),
        stream_(grpc::internal::ClientReaderWriterFactory<grpc::ByteBuffer, grpc::ByteBuffer>::Create(
            &channel,
            grpc::internal::RpcMethod("/fremen.v1.IngestService/Ingest", grpc::internal::RpcMethod::BIDI_STREAMING),
            context_.get())) {}

  bool Send(const std::string& bytes) {
    grpc::Slice slice(bytes);
    return stream_->Write(grpc::ByteBuffer(&slice, 1));
  }
  std::optional<v1::IngestResponse> Receive() {
    grpc::ByteBuffer buffer;
    v1::IngestResponse response;
    if (!stream_->Read(&buffer)) return std::nullopt;
    if (!grpc::SerializationTraits<v1::IngestResponse>::Deserialize(&buffer, &response).ok()) return std::nullopt;
    return response;
  }
  grpc::Status Finish() {
    stream_->WritesDone();
    grpc::ByteBuffer ignored;
    while (stream_->Read(&ignored)) {}
    return stream_->Finish();
  }

 private:
  std::unique_ptr<grpc::ClientContext> context_;
  std::unique_ptr<grpc::ClientReaderWriter<grpc::ByteBuffer, grpc::ByteBuffer>> stream_;
};

class IngestServiceTest : public DaemonTest {
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
  }
  void Restart(const std::vector<std::string>& args = {}) {
    StopDaemon();
    StartDaemon(args);
    Connect();
  }
  void Create(const v1::Map& map, const Metadata& metadata = {}) {
    v1::CreateMapRequest request;
    *request.mutable_map() = map;
    v1::CreateMapResponse response;
    const grpc::Status status = maps_->CreateMap(CallContext(metadata).get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  uint64_t Observations(const std::string& map) {
    v1::GetMapStatsRequest request;
    request.set_map(map);
    v1::GetMapStatsResponse response;
    const grpc::Status status = query_->GetMapStats(CallContext().get(), request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.stats().observations();
  }
  grpc::Status LastSequence(const std::string& map, uint64_t writer, uint64_t& last, const Metadata& metadata = {}) {
    v1::LastSequenceRequest request;
    request.set_map(map);
    request.set_writer_id(writer);
    v1::LastSequenceResponse response;
    const grpc::Status status = ingest_->LastSequence(CallContext(metadata).get(), request, &response);
    last = response.last_sequence();
    return status;
  }

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::IngestService::Stub> ingest_;
  std::unique_ptr<v1::QueryService::Stub> query_;
};

void ExpectAck(const v1::IngestResponse& response, uint64_t sequence, uint64_t accepted, uint64_t rejected = 0) {
  EXPECT_FALSE(response.has_error()) << response.error().message();
  EXPECT_EQ(response.sequence(), sequence);
  EXPECT_EQ(response.accepted(), accepted);
  EXPECT_EQ(response.rejected(), rejected);
  EXPECT_FALSE(response.duplicate());
}

void ExpectError(const v1::IngestResponse& response, uint64_t sequence, grpc::StatusCode code,
                 const std::string& message_part) {
  EXPECT_EQ(response.sequence(), sequence);
  EXPECT_EQ(response.error().code(), static_cast<int>(code)) << response.error().message();
  EXPECT_THAT(response.error().message(), HasSubstr(message_part));
  EXPECT_EQ(response.accepted(), 0u);
}

// --- scans of every kind ---

TEST_F(IngestServiceTest, CellsByIndexAreAcknowledged) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  ExpectAck(stream.Call(CellBatch("lab", 1, 1, {{0, 0, 0}, {39, 29, 3}, {5, 6, 2}}, {1, 0, 0.5f})), 1, 3);
  EXPECT_TRUE(stream.Close().ok());
}

TEST_F(IngestServiceTest, PointsAreAcknowledgedAndPointsOutsideTheGridRejected) {
  Create(GridMap("lab"));
  v1::IngestRequest request = Batch("lab", 1, 1);
  v1::Points* points = request.mutable_points()->mutable_points();
  const std::vector<std::array<double, 3>> xyz = {{0.1, 0.1, 0.1}, {19.9, 14.9, 1.9}, {20.1, 1, 1}, {1, -0.1, 1}};
  for (const auto& p : xyz) {
    points->add_x(p[0]);
    points->add_y(p[1]);
    points->add_z(p[2]);
    request.mutable_points()->add_values(1);
  }
  Stream stream(*ingest_);
  const v1::IngestResponse response = stream.Call(request);
  ExpectAck(response, 1, 2, 2);
  ASSERT_EQ(response.rejections_size(), 2);
  EXPECT_EQ(response.rejections(0).index(), 2u);
  EXPECT_EQ(response.rejections(0).reason(), v1::REJECT_REASON_OUTSIDE_MAP);
  EXPECT_EQ(response.rejections(1).index(), 3u);
  EXPECT_EQ(response.rejections(1).reason(), v1::REJECT_REASON_OUTSIDE_MAP);
}

TEST_F(IngestServiceTest, PatchesOfFloatsAndOfBytesAreAcknowledged) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  v1::IngestRequest floats = Batch("lab", 1, 1);
  floats.mutable_patch()->mutable_origin()->set_x(10);
  floats.mutable_patch()->mutable_size()->set_x(4);
  floats.mutable_patch()->mutable_size()->set_y(3);
  floats.mutable_patch()->mutable_size()->set_z(2);
  for (int i = 0; i < 24; ++i) floats.mutable_patch()->add_values(i % 2);
  ExpectAck(stream.Call(floats), 1, 24);

  v1::IngestRequest bytes = Batch("lab", 1, 2);
  bytes.mutable_patch()->mutable_size()->set_x(8);
  bytes.mutable_patch()->mutable_size()->set_y(8);
  bytes.mutable_patch()->set_probabilities(std::string(64, '\xff'));
  ExpectAck(stream.Call(bytes), 2, 64);
  EXPECT_TRUE(stream.Close().ok());
}

TEST_F(IngestServiceTest, StatesByIdAndByNameWithGroupsAreAcknowledged) {
  Create(GenericMap("doors"));
  Stream stream(*ingest_);
  v1::IngestRequest ids = Batch("doors", 1, 1);
  for (uint64_t id : {1u, 2u, 3u}) ids.mutable_states()->add_ids(id);
  for (float v : {1.0f, 0.0f, 1.0f}) ids.mutable_states()->add_values(v);
  for (const char* group : {"hall", "hall", "lab"}) ids.mutable_states()->add_groups(group);
  ExpectAck(stream.Call(ids), 1, 3);

  v1::IngestRequest named = Batch("doors", 1, 2);
  for (const char* name : {"front", "back"}) named.mutable_named_states()->add_names(name);
  for (float v : {0.0f, 1.0f}) named.mutable_named_states()->add_values(v);
  for (const char* group : {"hall", ""}) named.mutable_named_states()->add_groups(group);
  ExpectAck(stream.Call(named), 2, 2);
  EXPECT_TRUE(stream.Close().ok());
}

TEST_F(IngestServiceTest, PipelinedBatchesAreAnsweredInOrder) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  constexpr int kBatches = 100;
  // Writes block once the daemon stops reading (flow control): write from another thread.
  std::thread writer([&] {
    for (int i = 0; i < kBatches; ++i) ASSERT_TRUE(stream.Send(RowBatch("lab", 1, i)));
  });
  for (int i = 0; i < kBatches; ++i) {
    auto response = stream.Receive();
    ASSERT_TRUE(response.has_value()) << i;
    ExpectAck(*response, i, 40);
  }
  writer.join();
  EXPECT_TRUE(stream.Close().ok());
}

TEST_F(IngestServiceTest, MapMayComeFromTheHeader) {
  Create(GridMap("lab"));
  Stream stream(*ingest_, {{"x-fremen-map", "lab"}});
  ExpectAck(stream.Call(RowBatch("", 1, 1)), 1, 40);
  ExpectAck(stream.Call(RowBatch("lab", 1, 2)), 2, 40);
  stream.Send(RowBatch("other", 1, 3));
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("x-fremen-map"));
}

// --- retries ---

TEST_F(IngestServiceTest, RetriedBatchIsAcknowledgedAsDuplicate) {
  Create(GridMap("lab"));
  {
    Stream stream(*ingest_);
    ExpectAck(stream.Call(RowBatch("lab", 7, 1)), 1, 40);
    const v1::IngestResponse again = stream.Call(RowBatch("lab", 7, 1));
    EXPECT_TRUE(again.duplicate());
    EXPECT_EQ(again.sequence(), 1u);
    EXPECT_EQ(again.accepted(), 0u);
    // The same sequence from another writer is another batch.
    ExpectAck(stream.Call(RowBatch("lab", 8, 1)), 1, 40);
    EXPECT_TRUE(stream.Close().ok());
  }
  Stream reconnected(*ingest_);
  EXPECT_TRUE(reconnected.Call(RowBatch("lab", 7, 1)).duplicate());
  EXPECT_TRUE(reconnected.Close().ok());
}

TEST_F(IngestServiceTest, RestartKeepsIngestedData) {
  Create(GridMap("lab"));
  Create(GenericMap("doors"));
  {
    Stream stream(*ingest_);
    for (int i = 1; i <= 3; ++i) ExpectAck(stream.Call(RowBatch("lab", 7, i)), i, 40);
    EXPECT_TRUE(stream.Close().ok());
  }
  Restart();
  Stream stream(*ingest_);
  for (int i = 1; i <= 3; ++i) EXPECT_TRUE(stream.Call(RowBatch("lab", 7, i)).duplicate()) << i;
  ExpectAck(stream.Call(RowBatch("lab", 7, 4)), 4, 40);
  EXPECT_TRUE(stream.Close().ok());
}

// --- writers: a batch is a duplicate only if it is the same batch ---

// One cell of the map's top layer, which RowBatch never touches: new data under an old sequence.
v1::IngestRequest OtherBatch(const std::string& map, uint64_t writer, uint64_t sequence) {
  return CellBatch(map, writer, sequence, {{static_cast<uint32_t>(sequence % 40), 0, 3}}, {1.0f});
}

TEST_F(IngestServiceTest, AWriterThatRestartsItsCountIsToldWhereToContinueAndLosesNothing) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  for (uint64_t i = 1; i <= 10; ++i) ExpectAck(stream.Call(RowBatch("lab", 7, i)), i, 40);
  // The robot rebooted and lost its counter: new data as 1..5. Refused, never taken for retries.
  for (uint64_t i = 1; i <= 5; ++i) {
    const v1::IngestResponse response = stream.Call(OtherBatch("lab", 7, i));
    ExpectError(
        response, i, grpc::StatusCode::ALREADY_EXISTS,
        absl::StrCat("writer 7 sequence ", i, " was already used for a different batch; continue after sequence 10"));
    EXPECT_FALSE(response.duplicate());
  }
  // A true retry still is a duplicate, on the same stream as on a new one.
  EXPECT_TRUE(stream.Call(RowBatch("lab", 7, 4)).duplicate());
  EXPECT_EQ(Observations("lab"), 400u);
  // The writer learns where to continue, and its new data is applied from there.
  uint64_t last = 0;
  ASSERT_TRUE(LastSequence("lab", 7, last).ok());
  EXPECT_EQ(last, 10u);
  for (uint64_t i = 11; i <= 15; ++i) ExpectAck(stream.Call(OtherBatch("lab", 7, i)), i, 1);
  EXPECT_TRUE(stream.Close().ok());
  EXPECT_EQ(Observations("lab"), 405u);

  Restart();  // the window is kept with the map
  ASSERT_TRUE(LastSequence("lab", 7, last).ok());
  EXPECT_EQ(last, 15u);
  Stream after(*ingest_);
  EXPECT_TRUE(after.Call(OtherBatch("lab", 7, 12)).duplicate());
  ExpectError(after.Call(RowBatch("lab", 7, 12)), 12, grpc::StatusCode::ALREADY_EXISTS,
              "writer 7 sequence 12 was already used for a different batch; continue after sequence 15");
  EXPECT_TRUE(after.Close().ok());
  EXPECT_EQ(Observations("lab"), 405u);
}

TEST_F(IngestServiceTest, LastSequenceOfAnUnknownWriterIsZeroAndOfAnUnknownMapNotFound) {
  Create(GenericMap("doors"));
  uint64_t last = 99;
  ASSERT_TRUE(LastSequence("doors", 12345, last).ok());
  EXPECT_EQ(last, 0u);
  const grpc::Status missing = LastSequence("nowhere", 1, last);
  EXPECT_EQ(missing.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(missing.error_message(), HasSubstr("nowhere"));
}

// --- a message that is not an IngestRequest ends the stream ---

TEST_F(IngestServiceTest, AnUnparsableMessageEndsTheStreamWithInvalidArgumentNamingItsPosition) {
  Create(GridMap("lab"));
  RawStream stream(*channel_);
  const std::string first = RowBatch("lab", 3, 1).SerializeAsString();
  const std::string third = RowBatch("lab", 3, 3).SerializeAsString();
  std::string second = RowBatch("lab", 3, 2).SerializeAsString();
  second.resize(second.size() - 3);  // cut inside the packed values: truncated, not parsable
  ASSERT_FALSE(v1::IngestRequest().ParseFromString(second));
  ASSERT_TRUE(stream.Send(first));
  ASSERT_TRUE(stream.Send(second));
  stream.Send(third);  // may fail: the daemon may have ended the call already
  const auto answered = stream.Receive();
  ASSERT_TRUE(answered.has_value());
  ExpectAck(*answered, 1, 40);
  EXPECT_FALSE(stream.Receive().has_value());
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_THAT(status.error_message(), HasSubstr("message 2 of the stream: cannot parse IngestRequest"));
  // Neither the bad batch nor the one after it was applied; the daemon goes on serving.
  EXPECT_EQ(Observations("lab"), 40u);
  Stream next(*ingest_);
  ExpectAck(next.Call(RowBatch("lab", 3, 2)), 2, 40);
  ExpectAck(next.Call(RowBatch("lab", 3, 3)), 3, 40);
  EXPECT_TRUE(next.Close().ok());
}

// --- bad input: the batch is refused, the stream goes on ---

TEST_F(IngestServiceTest, BadTimesRefuseTheBatchAndTheStreamGoesOn) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  const double bad[] = {std::nan(""), std::numeric_limits<double>::infinity(),
                        -std::numeric_limits<double>::infinity(), 1.1e13, -1.1e13,
                        -1e9 /* before the epoch: docs/model.md, "Observations", calls it bad */};
  uint64_t sequence = 0;
  for (double t : bad) {
    v1::IngestRequest request = RowBatch("lab", 1, ++sequence);
    request.set_time(t);
    ExpectError(stream.Call(request), sequence, grpc::StatusCode::INVALID_ARGUMENT, "time");
  }
  v1::IngestRequest epoch = RowBatch("lab", 1, ++sequence);
  epoch.set_time(0);  // the epoch itself is a time
  ExpectAck(stream.Call(epoch), sequence, 40);
  ++sequence;
  ExpectAck(stream.Call(RowBatch("lab", 1, sequence)), sequence, 40);
  EXPECT_TRUE(stream.Close().ok());
}

TEST_F(IngestServiceTest, ValuesOutsideZeroOneAreRejectedOneByOne) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  const v1::IngestResponse response = stream.Call(
      CellBatch("lab", 1, 1, {{1, 1, 0}, {2, 1, 0}, {3, 1, 0}, {4, 1, 0}, {5, 1, 0}},
                {1.5f, 0.5f, -0.1f, std::nanf(""), std::numeric_limits<float>::infinity()}));
  ExpectAck(response, 1, 1, 4);
  ASSERT_EQ(response.rejections_size(), 4);
  const uint32_t indices[] = {0, 2, 3, 4};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(response.rejections(i).index(), indices[i]);
    EXPECT_EQ(response.rejections(i).reason(), v1::REJECT_REASON_VALUE_OUT_OF_RANGE);
  }
}

TEST_F(IngestServiceTest, CellsOutsideTheMapAreRejectedOneByOne) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  const v1::IngestResponse response =
      stream.Call(CellBatch("lab", 1, 1, {{40, 0, 0}, {0, 30, 0}, {0, 0, 4}, {(1u << 21) + 1, 1, 1}, {1, 1, 1}},
                            {1, 1, 1, 1, 1}));
  ExpectAck(response, 1, 1, 4);
  ASSERT_EQ(response.rejections_size(), 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(response.rejections(i).index(), static_cast<uint32_t>(i));
    EXPECT_EQ(response.rejections(i).reason(), v1::REJECT_REASON_OUTSIDE_MAP);
  }
}

TEST_F(IngestServiceTest, PatchOutsideTheGridIsOutOfRange) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  v1::IngestRequest request = Batch("lab", 1, 1);
  request.mutable_patch()->mutable_origin()->set_x(38);
  request.mutable_patch()->mutable_size()->set_x(4);
  request.mutable_patch()->mutable_size()->set_y(1);
  for (int i = 0; i < 4; ++i) request.mutable_patch()->add_values(1);
  ExpectError(stream.Call(request), 1, grpc::StatusCode::OUT_OF_RANGE, "patch along x");
  ExpectAck(stream.Call(RowBatch("lab", 1, 2)), 2, 40);
}

TEST_F(IngestServiceTest, MismatchedLengthsNameTheField) {
  Create(GridMap("lab"));
  Create(GenericMap("doors"));
  Stream stream(*ingest_);
  ExpectError(stream.Call(CellBatch("lab", 1, 1, {{1, 1, 0}, {2, 1, 0}, {3, 1, 0}, {4, 1, 0}}, {1, 1, 1})), 1,
              grpc::StatusCode::INVALID_ARGUMENT, "cells.values has 3 values for 4 cells");
  v1::IngestRequest short_y = RowBatch("lab", 1, 2);
  short_y.mutable_cells()->mutable_cells()->mutable_y()->RemoveLast();
  ExpectError(stream.Call(short_y), 2, grpc::StatusCode::INVALID_ARGUMENT, "cells.cells.y has 39 indices for 40");
  v1::IngestRequest patch = Batch("lab", 1, 3);
  patch.mutable_patch()->mutable_size()->set_x(2);
  patch.mutable_patch()->mutable_size()->set_y(2);
  patch.mutable_patch()->set_probabilities("abc");
  ExpectError(stream.Call(patch), 3, grpc::StatusCode::INVALID_ARGUMENT, "patch.probabilities has 3 bytes for 4");
  ExpectAck(stream.Call(RowBatch("lab", 1, 4)), 4, 40);
  EXPECT_TRUE(stream.Close().ok());

  Stream generic(*ingest_);
  v1::IngestRequest names = Batch("doors", 1, 1);
  names.mutable_named_states()->add_names("front");
  names.mutable_named_states()->add_values(1);
  names.mutable_named_states()->add_groups("a");
  names.mutable_named_states()->add_groups("b");
  ExpectError(generic.Call(names), 1, grpc::StatusCode::INVALID_ARGUMENT, "named_states.groups has 2 groups for 1");
  EXPECT_TRUE(generic.Close().ok());
}

TEST_F(IngestServiceTest, ObservationsOfTheWrongKindForTheMapAreRefused) {
  Create(GridMap("lab"));
  Create(GenericMap("doors"));
  Stream grid(*ingest_);
  v1::IngestRequest ids = Batch("lab", 1, 1);
  ids.mutable_states()->add_ids(1);
  ids.mutable_states()->add_values(1);
  ExpectError(grid.Call(ids), 1, grpc::StatusCode::INVALID_ARGUMENT, "only for generic maps");
  EXPECT_TRUE(grid.Close().ok());
  Stream generic(*ingest_);
  ExpectError(generic.Call(RowBatch("doors", 1, 1)), 1, grpc::StatusCode::INVALID_ARGUMENT,
              "cells are only for grid maps");
  EXPECT_TRUE(generic.Close().ok());
}

// --- bad input: the stream ends ---

TEST_F(IngestServiceTest, UnknownMapIsNotFound) {
  Stream stream(*ingest_);
  stream.Send(RowBatch("nowhere", 1, 1));
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(status.error_message(), HasSubstr("nowhere"));
}

TEST_F(IngestServiceTest, MissingMapIsInvalid) {
  Stream stream(*ingest_);
  stream.Send(RowBatch("", 1, 1));
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("map is required"));
}

TEST_F(IngestServiceTest, SwitchingMapsMidStreamEndsItAfterTheEarlierBatchesAreAnswered) {
  Create(GridMap("lab"));
  Create(GridMap("hall"));
  Stream stream(*ingest_);
  ASSERT_TRUE(stream.Send(RowBatch("lab", 1, 1)));
  ASSERT_TRUE(stream.Send(RowBatch("hall", 1, 2)));
  auto first = stream.Receive();
  ASSERT_TRUE(first.has_value());
  ExpectAck(*first, 1, 40);
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("map is \"hall\" but this stream ingests into \"lab\""));
}

TEST_F(IngestServiceTest, OversizedMessageIsResourceExhausted) {
  Restart({"--max-message-mb", "1"});
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  v1::IngestRequest big = Batch("lab", 1, 1);
  big.mutable_patch()->mutable_size()->set_x(40);
  big.mutable_patch()->mutable_size()->set_y(30);
  big.mutable_patch()->mutable_size()->set_z(4);
  big.mutable_patch()->set_probabilities(std::string(2 << 20, '\x01'));  // wrong count too, but too big first
  stream.Send(big);
  EXPECT_EQ(stream.Finish().error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  // The daemon goes on serving.
  Stream next(*ingest_);
  ExpectAck(next.Call(RowBatch("lab", 1, 1)), 1, 40);
}

TEST_F(IngestServiceTest, CancelledStreamLeavesTheDaemonServing) {
  Create(GridMap("lab"));
  {
    Stream stream(*ingest_);
    for (int i = 0; i < 20; ++i) stream.Send(RowBatch("lab", 1, i));
    stream.context().TryCancel();
    EXPECT_EQ(stream.Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  Stream next(*ingest_);
  const v1::IngestResponse response = next.Call(RowBatch("lab", 2, 1));
  ExpectAck(response, 1, 40);
  EXPECT_TRUE(next.Close().ok());
}

// --- shutdown ---

TEST_F(IngestServiceTest, SigtermEndsAnOpenStreamWithUnavailableAtOnce) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  ExpectAck(stream.Call(RowBatch("lab", 1, 1)), 1, 40);
  // The stream stays open and idle, as a robot's between scans; it must not hold shutdown for the
  // whole grace period.
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(daemon_->Stop(), 0) << daemon_->Log();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(status.error_message(), HasSubstr("shutting down"));
  EXPECT_THAT(daemon_->Log(), HasSubstr("Ingest"));
  EXPECT_THAT(daemon_->Log(), HasSubstr("batches=1 observations=40 rejected=0"));
  daemon_.reset();
}

TEST_F(IngestServiceTest, SigtermDuringIngestLosesNoAcknowledgedBatch) {
  Create(GridMap("lab"));
  Stream stream(*ingest_);
  std::atomic<uint64_t> sent{0};
  std::thread writer([&] {
    for (uint64_t i = 0; i < 100000 && stream.Send(RowBatch("lab", 1, i)); ++i) sent = i + 1;
  });
  std::set<uint64_t> acked;
  while (acked.size() < 20) {
    auto response = stream.Receive();
    ASSERT_TRUE(response.has_value());
    acked.insert(response->sequence());
  }
  EXPECT_EQ(daemon_->Stop(), 0);  // the writer goes on writing meanwhile
  while (auto response = stream.Receive()) acked.insert(response->sequence());
  writer.join();  // its writes fail once the stream has ended
  EXPECT_EQ(stream.Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
  daemon_.reset();
  StartDaemon();
  Connect();
  Stream resend(*ingest_);
  for (uint64_t i = 0; i < sent; ++i) {
    const v1::IngestResponse response = resend.Call(RowBatch("lab", 1, i));
    if (response.has_error()) {
      // Only a batch older than the sequences the map remembers of this writer may be refused:
      // the map then holds newer batches of the writer, which a stream applies in order after this
      // one, so it was not lost. (The writer may have sent more than that window before the stop.)
      EXPECT_THAT(response.error().message(), HasSubstr("older than the last")) << i;
      continue;
    }
    if (acked.count(i)) {
      EXPECT_TRUE(response.duplicate()) << i;
    }
  }
  EXPECT_TRUE(resend.Close().ok());
}

// --- tokens ---

class IngestTokenTest : public IngestServiceTest {
 protected:
  // Instead of IngestServiceTest's daemon, one that wants tokens.
  void SetUp() override {
    const std::string tokens = dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n");
    StartDaemon({"--tokens-file", tokens});
    if (!HasFatalFailure()) Connect();
  }
  static Metadata Bearer(const std::string& token) { return {{"authorization", "Bearer " + token}}; }
};

TEST_F(IngestTokenTest, IngestAndLastSequenceNeedAWriteToken) {
  Create(GridMap("lab"), Bearer("writer-token"));
  {
    Stream read_only(*ingest_, Bearer("reader-token"));
    read_only.Send(RowBatch("lab", 1, 1));
    const grpc::Status status = read_only.Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_THAT(status.error_message(), HasSubstr("Ingest needs a write token"));
  }
  {
    Stream anonymous(*ingest_);
    anonymous.Send(RowBatch("lab", 1, 1));
    EXPECT_EQ(anonymous.Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  Stream writer(*ingest_, Bearer("writer-token"));
  ExpectAck(writer.Call(RowBatch("lab", 1, 1)), 1, 40);
  EXPECT_TRUE(writer.Close().ok());
  uint64_t last = 0;
  const grpc::Status read_only = LastSequence("lab", 1, last, Bearer("reader-token"));
  EXPECT_EQ(read_only.error_code(), grpc::StatusCode::PERMISSION_DENIED) << read_only.error_message();
  ASSERT_TRUE(LastSequence("lab", 1, last, Bearer("writer-token")).ok());
  EXPECT_EQ(last, 1u);
}

// --- kill -9 ---

// A client that streams batches 0..n-1 of its own writer as fast as the daemon takes them and
// records which were acknowledged, until the daemon dies.
struct Client {
  uint64_t writer = 0;
  std::atomic<uint64_t> sent{0};
  std::set<uint64_t> acked;
  std::atomic<size_t> acked_count{0};
  // Acks that carried an error, and the first one's message: checked once Run has returned (Run
  // runs on a thread of its own, where a test assertion would not belong).
  size_t error_acks = 0;
  std::string first_error;

  void Run(v1::IngestService::Stub& stub, uint64_t n) {
    Stream stream(stub);
    std::thread sender([&] {
      for (uint64_t i = 0; i < n && stream.Send(RowBatch("lab", writer, i)); ++i) sent = i + 1;
    });
    while (auto response = stream.Receive()) {
      if (response->has_error() && error_acks++ == 0) first_error = response->error().message();
      acked.insert(response->sequence());
      ++acked_count;
    }
    stream.context().TryCancel();  // unblocks the sender
    sender.join();
    stream.Finish();
  }
};

TEST_F(IngestServiceTest, KillDuringIngestFromThreeClientsLosesNoAcknowledgedBatch) {
  Create(GridMap("lab"));
  constexpr uint64_t kBatches = 1000000;  // more than they can send before the kill
  std::array<Client, 3> clients;
  std::vector<std::thread> threads;
  for (size_t c = 0; c < clients.size(); ++c) {
    clients[c].writer = 100 + c;
    threads.emplace_back([&, c] { clients[c].Run(*ingest_, kBatches); });
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  auto acked_each = [&](size_t n) {
    for (const Client& client : clients) {
      if (client.acked_count < n) return false;
    }
    return true;
  };
  while (!acked_each(50) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // Asserted once the clients' threads are joined: returning with them running would abort.
  const bool each_acked = acked_each(50);
  daemon_->Kill();
  for (std::thread& t : threads) t.join();
  daemon_.reset();
  ASSERT_TRUE(each_acked) << "a client had fewer than 50 acks after a minute";
  for (const Client& client : clients) EXPECT_EQ(client.error_acks, 0u) << client.first_error;

  StartDaemon();
  Connect();
  uint64_t sent = 0;
  for (const Client& client : clients) {
    Stream stream(*ingest_);
    uint64_t applied_now = 0;
    sent += client.sent;
    for (uint64_t i = 0; i < client.sent; ++i) {
      const v1::IngestResponse response = stream.Call(RowBatch("lab", client.writer, i));
      // A batch applied before is a duplicate or, below the window of the writer's sequences the
      // map remembers (the clients here had far more in flight than the client libraries allow),
      // refused as too old to tell from new data. Either way it is not applied again.
      if (response.has_error()) {
        ASSERT_EQ(response.error().code(), static_cast<int>(grpc::StatusCode::ALREADY_EXISTS))
            << response.error().message();
        EXPECT_THAT(response.error().message(), HasSubstr("older than the last"));
      }
      const bool applied = !response.duplicate() && !response.has_error();
      if (client.acked.count(i)) {
        EXPECT_FALSE(applied) << "acknowledged batch " << i << " of writer " << client.writer << " lost";
      } else if (applied) {
        EXPECT_EQ(response.accepted(), 40u);
        ++applied_now;
      }
    }
    // Everything is applied now, exactly once: the writer's recent batches are duplicates.
    for (uint64_t i = client.sent > kWriterWindow ? client.sent - kWriterWindow : 0; i < client.sent; ++i) {
      EXPECT_TRUE(stream.Call(RowBatch("lab", client.writer, i)).duplicate()) << i;
    }
    EXPECT_TRUE(stream.Close().ok());
    RecordProperty("writer_" + std::to_string(client.writer),
                   absl::StrCat(client.acked.size(), " acked of ", client.sent.load(), " sent; ", applied_now,
                                " applied on resend"));
  }
  // ... and the map holds every batch's 40 observations once.
  EXPECT_EQ(Observations("lab"), 40 * sent);
}

}  // namespace
}  // namespace fremen::testing
