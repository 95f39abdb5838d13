// The JSON API (server/gateway/) end to end: a real fremend, real HTTP over loopback with
// cpp-httplib's client. Every route of docs/http.md's table is called and its answer compared
// with what the gRPC service answers for the same request; the bad-input rows carry the HTTP
// status, the gRPC code and the gRPC message; the token roles are gRPC's (no token 401, a read
// token may view but not act, 403; a write token may do both); region.png, decoded, is the JSON
// region drawn with base/gray_levels.h, row 0 the highest y.
#include <arpa/inet.h>
#include <google/protobuf/struct.pb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "base/gray_levels.h"
#include "client/formats/png_decode.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/fremend_fixture.h"
#include "tests/http_client.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

constexpr double kT0 = 1.7e9;
constexpr uint32_t kWidth = 20, kHeight = 10;
constexpr int kBatches = 24;  // a day of hourly scans: the door cell (3, 4) open by day

struct Answer {
  int status = 0;
  std::string body;
  std::string content_type;
  std::string allow;
};

template <typename M>
std::string Json(const M& message) {
  std::string json;
  EXPECT_TRUE(google::protobuf::util::MessageToJsonString(message, &json).ok());
  return json;
}

template <typename M>
M Parse(const Answer& answer) {
  M message;
  const auto parsed = google::protobuf::util::JsonStringToMessage(answer.body, &message);
  EXPECT_TRUE(parsed.ok()) << parsed.ToString() << ": " << answer.body;
  return message;
}

template <typename M>
void ExpectSame(const M& over_http, const M& over_grpc) {
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(over_http, over_grpc))
      << "HTTP:\n" << over_http.DebugString() << "gRPC:\n" << over_grpc.DebugString();
}

class HttpApiTest : public DaemonTest {
 protected:
  Answer Call(const std::string& method, const std::string& path, const std::string& body = "",
              const httplib::Headers& headers = {}) {
    httplib::Client client = HttpClientFor(daemon_->http_address());
    client.set_read_timeout(60);
    httplib::Result result = method == "GET"      ? client.Get(path, headers)
                             : method == "POST"   ? client.Post(path, headers, body, "application/json")
                             : method == "DELETE" ? client.Delete(path, headers)
                             : method == "PUT"    ? client.Put(path, headers, body, "application/json")
                                                  : client.Patch(path, headers, body, "application/json");
    EXPECT_TRUE(result) << method << " " << path << ": " << httplib::to_string(result.error());
    if (!result) return {};
    return {result->status, result->body, result->get_header_value("Content-Type"), result->get_header_value("Allow")};
  }
  // A call expected to succeed.
  template <typename M>
  M Ok(const std::string& method, const std::string& path, const std::string& body = "",
       const httplib::Headers& headers = {}) {
    const Answer answer = Call(method, path, body, headers);
    EXPECT_EQ(answer.status, 200) << method << " " << path << ": " << answer.body;
    EXPECT_EQ(answer.content_type, "application/json");
    return Parse<M>(answer);
  }

  void CreateOverHttp(const v1::Map& map) {
    v1::CreateMapRequest request;
    *request.mutable_map() = map;
    const auto created = Ok<v1::CreateMapResponse>("POST", "/v1/maps", Json(request));
    ASSERT_EQ(created.map().name(), map.name());
  }

  // kBatches hourly scans of the whole grid over HTTP: walls (x = 0) occupied, the door cell
  // (3, 4) open from 8:00 to 18:00, the rest free.
  void FillGridOverHttp(const std::string& map) {
    for (int b = 0; b < kBatches; ++b) {
      v1::IngestRequest request;
      request.set_writer_id(7);
      request.set_sequence(b + 1);
      request.set_time(kT0 + 3600.0 * b);
      for (uint32_t y = 0; y < kHeight; ++y) {
        for (uint32_t x = 0; x < kWidth; ++x) {
          request.mutable_cells()->mutable_cells()->add_x(x);
          request.mutable_cells()->mutable_cells()->add_y(y);
          const bool door_closed = x == 3 && y == 4 && (b < 8 || b >= 18);
          request.mutable_cells()->add_values(x == 0 || door_closed ? 1.0f : 0.0f);
        }
      }
      const auto response = Ok<v1::IngestResponse>("POST", absl::StrCat("/v1/maps/", map, ":ingest"), Json(request));
      ASSERT_EQ(response.accepted(), kWidth * kHeight) << response.DebugString();
      ASSERT_EQ(response.sequence(), static_cast<uint64_t>(b + 1));
    }
  }

  // RunUpdate over HTTP, then GET the operation until it is done.
  v1::Operation UpdateOverHttp(const std::string& map) {
    v1::Operation operation = Ok<v1::Operation>("POST", absl::StrCat("/v1/maps/", map, ":runUpdate"), "{}");
    EXPECT_EQ(operation.map(), map);
    // Polled at the job's own pace (a hung job fails at ctest's timeout, not a timed assertion).
    while (!operation.done() && !::testing::Test::HasFailure()) {
      operation = Ok<v1::Operation>("GET", absl::StrCat("/v1/maps/", map, "/", operation.name()));
    }
    EXPECT_EQ(operation.error().code(), 0) << operation.error().message();
    return operation;
  }

  // PredictRegion over gRPC, its chunks joined.
  v1::PredictRegionResponse RegionOverGrpc(v1::PredictRegionRequest request) {
    auto query = v1::QueryService::NewStub(daemon_->NewChannel());
    auto context = CallContext();
    auto reader = query->PredictRegion(context.get(), request);
    v1::PredictRegionResponse joined, chunk;
    while (reader->Read(&chunk)) {
      joined.set_box_cells(chunk.box_cells());
      joined.mutable_float_values()->Add(chunk.float_values().begin(), chunk.float_values().end());
      joined.mutable_bytes_values()->append(chunk.bytes_values());
    }
    const grpc::Status status = reader->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    return joined;
  }

  std::unique_ptr<v1::MapService::Stub> maps() { return v1::MapService::NewStub(daemon_->NewChannel()); }
  std::unique_ptr<v1::QueryService::Stub> query() { return v1::QueryService::NewStub(daemon_->NewChannel()); }
  std::unique_ptr<v1::AdminService::Stub> admin() { return v1::AdminService::NewStub(daemon_->NewChannel()); }
};

TEST_F(HttpApiTest, MapRoutesAnswerWhatMapServiceAnswers) {
  CreateOverHttp(GridMapSpec("lab", kWidth, kHeight, 0.5));
  CreateOverHttp(GenericMapSpec("rooms"));
  v1::GetMapRequest get;
  get.set_map("lab");
  v1::GetMapResponse over_grpc;
  ASSERT_TRUE(maps()->GetMap(CallContext().get(), get, &over_grpc).ok());
  ExpectSame(Ok<v1::GetMapResponse>("GET", "/v1/maps/lab"), over_grpc);

  v1::ListMapsRequest list;
  list.set_page_size(1);
  v1::ListMapsResponse first_page;
  ASSERT_TRUE(maps()->ListMaps(CallContext().get(), list, &first_page).ok());
  ExpectSame(Ok<v1::ListMapsResponse>("GET", "/v1/maps?page_size=1"), first_page);
  list.set_page_token(first_page.next_page_token());
  v1::ListMapsResponse second_page;
  ASSERT_TRUE(maps()->ListMaps(CallContext().get(), list, &second_page).ok());
  ExpectSame(Ok<v1::ListMapsResponse>("GET", "/v1/maps?pageSize=1&page_token=" + first_page.next_page_token()),
             second_page);
  EXPECT_EQ(second_page.maps(0).name(), "rooms");

  Ok<v1::DeleteMapResponse>("DELETE", "/v1/maps/rooms");
  get.set_map("rooms");
  EXPECT_EQ(maps()->GetMap(CallContext().get(), get, &over_grpc).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(HttpApiTest, GridQueriesAnswerWhatQueryServiceAnswers) {
  CreateOverHttp(GridMapSpec("lab", kWidth, kHeight, 0.5));
  FillGridOverHttp("lab");
  ASSERT_FALSE(HasFatalFailure());
  UpdateOverHttp("lab");

  // lastSequence
  auto ingest = v1::IngestService::NewStub(daemon_->NewChannel());
  v1::LastSequenceRequest last;
  last.set_map("lab");
  last.set_writer_id(7);
  v1::LastSequenceResponse last_grpc;
  ASSERT_TRUE(ingest->LastSequence(CallContext().get(), last, &last_grpc).ok());
  EXPECT_EQ(last_grpc.last_sequence(), static_cast<uint64_t>(kBatches));
  ExpectSame(Ok<v1::LastSequenceResponse>("GET", "/v1/maps/lab/writers/7/lastSequence"), last_grpc);

  // stats (the sizes in bytes move with checkpoints: the counts are compared)
  v1::GetMapStatsRequest stats;
  stats.set_map("lab");
  v1::GetMapStatsResponse stats_grpc;
  ASSERT_TRUE(query()->GetMapStats(CallContext().get(), stats, &stats_grpc).ok());
  const auto stats_http = Ok<v1::GetMapStatsResponse>("GET", "/v1/maps/lab/stats");
  EXPECT_EQ(stats_http.stats().states(), stats_grpc.stats().states());
  EXPECT_EQ(stats_http.stats().dynamic_states(), stats_grpc.stats().dynamic_states());
  EXPECT_EQ(stats_http.stats().observations(), uint64_t{kBatches} * kWidth * kHeight);
  ExpectSame(stats_http.stats().last_update(), stats_grpc.stats().last_update());

  // :predict, with 64-bit and repeated fields in the body
  v1::PredictRequest predict;
  predict.set_map("lab");
  for (uint32_t x : {0u, 3u, 5u}) {
    predict.mutable_states()->mutable_cells()->add_x(x);
    predict.mutable_states()->mutable_cells()->add_y(4);
  }
  for (int h : {3, 9, 12}) predict.add_times(kT0 + 86400.0 + 3600.0 * h);
  v1::PredictResponse predict_grpc;
  ASSERT_TRUE(query()->Predict(CallContext().get(), predict, &predict_grpc).ok());
  ExpectSame(Ok<v1::PredictResponse>("POST", "/v1/maps/lab:predict", Json(predict)), predict_grpc);
  predict.clear_map();  // the path names it
  ExpectSame(Ok<v1::PredictResponse>("POST", "/v1/maps/lab:predict", Json(predict)), predict_grpc);

  // region: FLOAT in several chunks, and UINT8
  v1::PredictRegionRequest region;
  region.set_map("lab");
  region.mutable_hi()->set_x(kWidth);
  region.mutable_hi()->set_y(kHeight);
  region.set_time(kT0 + 86400.0 + 3600.0 * 3);
  region.set_chunk_cells(7);
  const v1::PredictRegionResponse region_grpc = RegionOverGrpc(region);
  const std::string region_query = absl::StrCat("hi.x=", kWidth, "&hi.y=", kHeight, "&time=", kT0 + 86400.0 + 3600.0 * 3);
  const auto region_http = Ok<v1::PredictRegionResponse>("GET", "/v1/maps/lab/region?chunk_cells=7&" + region_query);
  ExpectSame(region_http, region_grpc);
  EXPECT_EQ(region_http.box_cells(), uint64_t{kWidth} * kHeight);
  region.set_output(v1::REGION_OUTPUT_UINT8);
  ExpectSame(Ok<v1::PredictRegionResponse>("GET", "/v1/maps/lab/region?output=REGION_OUTPUT_UINT8&" + region_query),
             RegionOverGrpc(region));

  // region.png: the JSON region drawn, pixel by pixel, in each mode
  struct Mode {
    std::string name;
    v1::RegionOutput output;
  };
  for (const Mode& mode : {Mode{"probability", v1::REGION_OUTPUT_FLOAT}, Mode{"entropy", v1::REGION_OUTPUT_ENTROPY},
                           Mode{"state", v1::REGION_OUTPUT_STATES}}) {
    const std::string query = absl::StrCat(region_query, "&confidence=0.5");
    const Answer png = Call("GET", absl::StrCat("/v1/maps/lab/region.png?mode=", mode.name, "&", query));
    ASSERT_EQ(png.status, 200) << png.body;
    EXPECT_EQ(png.content_type, "image/png");
    auto image = formats::DecodePng(png.body);
    ASSERT_TRUE(image.ok()) << image.status();
    ASSERT_EQ(image->width, static_cast<int>(kWidth));
    ASSERT_EQ(image->height, static_cast<int>(kHeight));
    ASSERT_EQ(image->channels, 1);
    const auto values = Ok<v1::PredictRegionResponse>(
        "GET", absl::StrCat("/v1/maps/lab/region?output=", v1::RegionOutput_Name(mode.output), "&", query));
    for (uint32_t y = 0; y < kHeight; ++y) {
      for (uint32_t x = 0; x < kWidth; ++x) {
        const int cell = static_cast<int>(y * kWidth + x);
        const double v = mode.output == v1::REGION_OUTPUT_STATES
                             ? static_cast<uint8_t>(values.bytes_values()[cell])
                             : values.float_values(cell);
        ASSERT_EQ(image->at(static_cast<int>(x), static_cast<int>(kHeight - 1 - y)), GrayLevel(v))
            << mode.name << " cell (" << x << ", " << y << ")";
      }
    }
    if (mode.name == "probability") {
      // The wall is dark and the floor light; at 03:00 the door is closed (dark).
      EXPECT_LT(image->at(0, 0), 64);
      EXPECT_GT(image->at(10, 0), 192);
      EXPECT_LT(image->at(3, kHeight - 1 - 4), 128);
    }
  }

  // model, by cell in query parameters
  v1::GetStateModelRequest model;
  model.set_map("lab");
  model.mutable_state()->mutable_cell()->set_x(3);
  model.mutable_state()->mutable_cell()->set_y(4);
  model.set_include_spectrum(true);
  v1::GetStateModelResponse model_grpc;
  ASSERT_TRUE(query()->GetStateModel(CallContext().get(), model, &model_grpc).ok());
  ExpectSame(Ok<v1::GetStateModelResponse>("GET", "/v1/maps/lab/model?state.cell.x=3&state.cell.y=4&include_spectrum=true"),
             model_grpc);
  EXPECT_FALSE(model_grpc.model().never_changed());

  // :checkAnomalies
  v1::CheckAnomaliesRequest anomalies;
  anomalies.mutable_states()->mutable_cells()->add_x(3);
  anomalies.mutable_states()->mutable_cells()->add_y(4);
  anomalies.add_values(1.0f);
  anomalies.add_times(kT0 + 86400.0 + 3600.0 * 12);
  anomalies.set_confidence(0.9f);
  v1::CheckAnomaliesResponse anomalies_http =
      Ok<v1::CheckAnomaliesResponse>("POST", "/v1/maps/lab:checkAnomalies", Json(anomalies));
  anomalies.set_map("lab");
  v1::CheckAnomaliesResponse anomalies_grpc;
  ASSERT_TRUE(query()->CheckAnomalies(CallContext().get(), anomalies, &anomalies_grpc).ok());
  ExpectSame(anomalies_http, anomalies_grpc);
}

TEST_F(HttpApiTest, GenericMapQueriesAnswerWhatQueryServiceAnswers) {
  CreateOverHttp(GenericMapSpec("rooms"));
  for (int b = 0; b < kBatches; ++b) {
    v1::IngestRequest request;
    request.set_writer_id(1);
    request.set_sequence(b + 1);
    request.set_time(kT0 + 3600.0 * b);
    for (const char* name : {"kitchen", "office", "lab"}) {
      request.mutable_named_states()->add_names(name);
      request.mutable_named_states()->add_groups("rooms");
      request.mutable_named_states()->add_values(name[0] == 'o' && b >= 8 && b < 18 ? 1.0f : 0.0f);
    }
    ASSERT_EQ(Ok<v1::IngestResponse>("POST", "/v1/maps/rooms:ingest", Json(request)).accepted(), 3u);
  }
  UpdateOverHttp("rooms");

  v1::ListStatesRequest states;
  states.set_map("rooms");
  states.set_group("rooms");
  states.set_page_size(2);
  v1::ListStatesResponse states_grpc;
  ASSERT_TRUE(query()->ListStates(CallContext().get(), states, &states_grpc).ok());
  EXPECT_EQ(states_grpc.total(), 3u);
  ExpectSame(Ok<v1::ListStatesResponse>("GET", "/v1/maps/rooms/states?group=rooms&page_size=2"), states_grpc);

  v1::TopStatesRequest top;
  top.set_map("rooms");
  top.set_group("rooms");
  top.set_n(2);
  top.set_time(kT0 + 86400.0 + 3600.0 * 12);
  v1::TopStatesResponse top_grpc;
  ASSERT_TRUE(query()->TopStates(CallContext().get(), top, &top_grpc).ok());
  ASSERT_EQ(top_grpc.states_size(), 2);
  EXPECT_EQ(top_grpc.states(0).name(), "office");
  ExpectSame(Ok<v1::TopStatesResponse>("POST", "/v1/maps/rooms:topStates", Json(top)), top_grpc);

  // model by name
  v1::GetStateModelRequest model;
  model.set_map("rooms");
  model.mutable_state()->set_name("office");
  v1::GetStateModelResponse model_grpc;
  ASSERT_TRUE(query()->GetStateModel(CallContext().get(), model, &model_grpc).ok());
  ExpectSame(Ok<v1::GetStateModelResponse>("GET", "/v1/maps/rooms/model?state.name=office"), model_grpc);
}

TEST_F(HttpApiTest, ReconstructOnALosslessMap) {
  v1::Map map = GridMapSpec("lab", kWidth, kHeight, 0.5);
  map.set_lossless_sampling_seconds(3600);
  map.set_lossless_origin(kT0);
  CreateOverHttp(map);
  FillGridOverHttp("lab");
  ASSERT_FALSE(HasFatalFailure());
  v1::ReconstructRequest reconstruct;
  reconstruct.set_map("lab");
  reconstruct.mutable_states()->mutable_cells()->add_x(3);
  reconstruct.mutable_states()->mutable_cells()->add_y(4);
  reconstruct.set_start_time(kT0);
  reconstruct.set_end_time(kT0 + 3600.0 * kBatches);
  v1::ReconstructResponse reconstruct_grpc;
  const grpc::Status status = query()->Reconstruct(CallContext().get(), reconstruct, &reconstruct_grpc);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(reconstruct_grpc.histories_size(), 1);
  EXPECT_FALSE(reconstruct_grpc.histories(0).slots().empty());
  ExpectSame(Ok<v1::ReconstructResponse>("POST", "/v1/maps/lab:reconstruct", Json(reconstruct)), reconstruct_grpc);
}

TEST_F(HttpApiTest, OperationRoutesAnswerWhatAdminServiceAnswers) {
  CreateOverHttp(GridMapSpec("lab", kWidth, kHeight, 0.5));
  FillGridOverHttp("lab");
  ASSERT_FALSE(HasFatalFailure());
  const v1::Operation done = UpdateOverHttp("lab");
  ASSERT_TRUE(done.done());
  EXPECT_GT(done.update().states_published(), 0u);

  v1::GetOperationRequest get;
  get.set_map("lab");
  get.set_name(done.name());
  v1::Operation get_grpc;
  ASSERT_TRUE(admin()->GetOperation(CallContext().get(), get, &get_grpc).ok());
  ExpectSame(done, get_grpc);

  v1::ListOperationsRequest list;
  v1::ListOperationsResponse all_grpc;
  ASSERT_TRUE(admin()->ListOperations(CallContext().get(), list, &all_grpc).ok());
  ExpectSame(Ok<v1::ListOperationsResponse>("GET", "/v1/operations"), all_grpc);
  list.set_map("lab");
  v1::ListOperationsResponse map_grpc;
  ASSERT_TRUE(admin()->ListOperations(CallContext().get(), list, &map_grpc).ok());
  ASSERT_EQ(map_grpc.operations_size(), 1);
  ExpectSame(Ok<v1::ListOperationsResponse>("GET", "/v1/maps/lab/operations"), map_grpc);
  list.set_running_only(true);
  ASSERT_TRUE(admin()->ListOperations(CallContext().get(), list, &map_grpc).ok());
  EXPECT_EQ(map_grpc.operations_size(), 0);
  ExpectSame(Ok<v1::ListOperationsResponse>("GET", "/v1/maps/lab/operations?running_only=true"), map_grpc);

  // Cancelling a finished operation: whatever gRPC answers, HTTP answers the same.
  v1::CancelOperationRequest cancel;
  cancel.set_map("lab");
  cancel.set_name(done.name());
  v1::Operation cancel_grpc;
  const grpc::Status cancelled = admin()->CancelOperation(CallContext().get(), cancel, &cancel_grpc);
  const Answer cancel_http = Call("POST", absl::StrCat("/v1/maps/lab/", done.name(), ":cancel"), "{}");
  if (cancelled.ok()) {
    EXPECT_EQ(cancel_http.status, 200) << cancel_http.body;
    ExpectSame(Parse<v1::Operation>(cancel_http), cancel_grpc);
  } else {
    EXPECT_NE(cancel_http.status, 200);
    EXPECT_THAT(cancel_http.body, HasSubstr(cancelled.error_message()));
  }

  const Answer missing = Call("GET", "/v1/maps/lab/operations/update-lab-99");
  EXPECT_EQ(missing.status, 404) << missing.body;
  EXPECT_THAT(missing.body, HasSubstr("no operation named \\\"operations/update-lab-99\\\""));
}

TEST_F(HttpApiTest, AdminRoutesAnswerWhatAdminServiceAnswers) {
  CreateOverHttp(GridMapSpec("lab", kWidth, kHeight, 0.5));
  FillGridOverHttp("lab");
  ASSERT_FALSE(HasFatalFailure());

  v1::GetServerStatusResponse status_grpc;
  ASSERT_TRUE(admin()->GetServerStatus(CallContext().get(), {}, &status_grpc).ok());
  const auto status_http = Ok<v1::GetServerStatusResponse>("GET", "/v1/status");
  EXPECT_EQ(status_http.version(), status_grpc.version());
  EXPECT_EQ(status_http.map_count(), 1u);
  EXPECT_EQ(status_http.state_count(), status_grpc.state_count());
  EXPECT_EQ(status_http.update_schedule(), status_grpc.update_schedule());
  ExpectSame(status_http.start_time(), status_grpc.start_time());
  EXPECT_EQ(status_http.store_state(), v1::STORE_STATE_OPEN);

  v1::CheckMapRequest check;
  check.set_map("lab");
  v1::CheckMapResponse check_grpc;
  ASSERT_TRUE(admin()->CheckMap(CallContext().get(), check, &check_grpc).ok());
  v1::CheckMapResponse check_http = Ok<v1::CheckMapResponse>("POST", "/v1/maps/lab:check", "{}");
  EXPECT_TRUE(check_http.clean());
  check_http.clear_duration_seconds();
  check_grpc.clear_duration_seconds();
  ExpectSame(check_http, check_grpc);

  const auto backup = Ok<v1::BackupMapResponse>("POST", "/v1/maps/lab:backup", R"({"directory": "http-backup"})");
  EXPECT_GT(backup.bytes(), 0u);
  EXPECT_TRUE(std::filesystem::exists(backup.path())) << backup.path();
  v1::BackupMapRequest again;
  again.set_map("lab");
  again.set_directory("http-backup");
  v1::BackupMapResponse again_grpc;
  const grpc::Status again_status = admin()->BackupMap(CallContext().get(), again, &again_grpc);
  const Answer again_http = Call("POST", "/v1/maps/lab:backup", R"({"directory": "http-backup"})");
  if (!again_status.ok()) {
    EXPECT_EQ(again_http.status == 409 || again_http.status == 400, true) << again_http.body;
    EXPECT_THAT(again_http.body, HasSubstr(absl::StrCat("\"code\":", static_cast<int>(again_status.error_code()))));
  }

  // Salvage copies a damaged map (SalvageOfADamagedMapReportsWhatGrpcReports); of a healthy map the
  // answer is gRPC's refusal, code and message.
  v1::SalvageMapRequest salvage;
  salvage.set_map("lab");
  salvage.set_new_map("lab2");
  v1::SalvageMapResponse salvage_grpc;
  const grpc::Status salvage_status = admin()->SalvageMap(CallContext().get(), salvage, &salvage_grpc);
  ASSERT_EQ(salvage_status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << salvage_status.error_message();
  const Answer salvage_http = Call("POST", "/v1/maps/lab:salvage", R"({"newMap": "lab2"})");
  EXPECT_EQ(salvage_http.status, 400);
  const auto salvage_body = Parse<google::protobuf::Struct>(salvage_http);
  EXPECT_EQ(salvage_body.fields().at("code").number_value(), 9);
  EXPECT_EQ(salvage_body.fields().at("message").string_value(), salvage_status.error_message());

  v1::GetMapRequest get;
  Ok<v1::DeleteMapResponse>("DELETE", "/v1/maps/lab");
  const auto restored = Ok<v1::RestoreMapResponse>("POST", "/v1/maps/lab:restore", R"({"directory": "http-backup"})");
  EXPECT_EQ(restored.map().name(), "lab");
  get.set_map("lab");
  v1::GetMapResponse lab;
  ASSERT_TRUE(maps()->GetMap(CallContext().get(), get, &lab).ok());
  ExpectSame(restored.map(), lab.map());
  EXPECT_EQ(Ok<v1::GetMapStatsResponse>("GET", "/v1/maps/lab/stats").stats().observations(),
            uint64_t{kBatches} * kWidth * kHeight);
}

// The only map directory of the (stopped) daemon's data directory.
std::string OnlyMapDir(const std::string& data_dir) {
  std::vector<std::filesystem::path> dirs;
  for (const auto& e : std::filesystem::directory_iterator(data_dir + "/maps")) dirs.push_back(e.path());
  EXPECT_EQ(dirs.size(), 1u);
  return dirs.empty() ? "" : dirs.front().string();
}

TEST_F(HttpApiTest, SalvageOfADamagedMapReportsWhatGrpcReports) {
  constexpr uint32_t kX = 64, kY = 32;
  v1::Map map = GridMapSpec("lab", kX, kY, 0.1);
  map.set_shards(1);
  CreateOverHttp(map);
  for (int i = 0; i < 7; ++i) {  // scans of dense patches (bytes as base64 in the JSON body)
    v1::IngestRequest scan;
    scan.set_writer_id(3);
    scan.set_sequence(i + 1);
    scan.set_time(kT0 + 3600.0 * i);
    scan.mutable_patch()->mutable_size()->set_x(kX);
    scan.mutable_patch()->mutable_size()->set_y(kY);
    scan.mutable_patch()->mutable_size()->set_z(1);
    scan.mutable_patch()->set_probabilities(std::string(uint64_t{kX} * kY, i % 2 == 1 && i < 6 ? '\xff' : '\0'));
    ASSERT_EQ(Ok<v1::IngestResponse>("POST", "/v1/maps/lab:ingest", Json(scan)).accepted(), uint64_t{kX} * kY);
  }
  StopDaemon();
  // A page in the middle of the shard zeroed, as a disk would (tests/check_test.cc).
  const std::string shard = OnlyMapDir(data_dir()) + "/shard-0/data.mdb";
  const uint64_t pages = std::filesystem::file_size(shard) / 4096;
  ASSERT_GT(pages, 16u);
  {
    std::fstream file(shard, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(static_cast<std::streamoff>(pages / 2 * 4096));
    const std::string zeros(4096, '\0');
    file.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
  }
  StartDaemon();
  ASSERT_FALSE(HasFatalFailure());
  const auto status = Ok<v1::GetServerStatusResponse>("GET", "/v1/status");
  ASSERT_EQ(status.failed_maps_size(), 1);
  EXPECT_EQ(status.failed_maps(0).map(), "lab");

  auto salvaged = Ok<v1::SalvageMapResponse>("POST", "/v1/maps/lab:salvage", R"({"newMap": "lab-http"})");
  EXPECT_EQ(salvaged.map().name(), "lab-http");
  EXPECT_GT(salvaged.records_kept(), 0u);
  EXPECT_GT(salvaged.losses(), 0u);
  v1::SalvageMapRequest request;
  request.set_map("lab");
  request.set_new_map("lab-grpc");
  v1::SalvageMapResponse salvaged_grpc;
  const grpc::Status done = admin()->SalvageMap(CallContext().get(), request, &salvaged_grpc);
  ASSERT_TRUE(done.ok()) << done.error_message();
  // The same damage, the same report: all but the new map's name, creation time and the duration.
  for (v1::SalvageMapResponse* report : {&salvaged, &salvaged_grpc}) {
    report->clear_map();
    report->clear_duration_seconds();
  }
  ExpectSame(salvaged, salvaged_grpc);
  v1::GetMapRequest get;
  get.set_map("lab-http");
  v1::GetMapResponse served;
  EXPECT_TRUE(maps()->GetMap(CallContext().get(), get, &served).ok());
}

// The message gRPC gives for `call` (expected to fail with `code`).
template <typename Call>
std::string GrpcMessage(grpc::StatusCode code, Call call) {
  const grpc::Status status = call();
  EXPECT_EQ(status.error_code(), code) << status.error_message();
  return status.error_message();
}

TEST_F(HttpApiTest, BadInputsAreTheirGrpcStatusWithItsMessage) {
  CreateOverHttp(GridMapSpec("lab", kWidth, kHeight, 0.5));
  CreateOverHttp(GenericMapSpec("rooms"));
  const std::string unknown_map = GrpcMessage(grpc::StatusCode::NOT_FOUND, [&] {
    v1::GetMapRequest get;
    get.set_map("nope");
    v1::GetMapResponse ignored;
    return maps()->GetMap(CallContext().get(), get, &ignored);
  });
  const std::string grid_only = GrpcMessage(grpc::StatusCode::FAILED_PRECONDITION, [&] {
    v1::PredictRegionRequest region;
    region.set_map("rooms");
    region.mutable_hi()->set_x(1);
    region.mutable_hi()->set_y(1);
    auto context = CallContext();
    v1::PredictRegionResponse chunk;
    auto reader = query()->PredictRegion(context.get(), region);
    while (reader->Read(&chunk)) {
    }
    return reader->Finish();
  });
  const std::string no_kind = GrpcMessage(grpc::StatusCode::INVALID_ARGUMENT, [&] {
    v1::CreateMapRequest create;
    create.mutable_map()->set_name("kindless");
    v1::CreateMapResponse ignored;
    return maps()->CreateMap(CallContext().get(), create, &ignored);
  });
  struct Row {
    std::string method, path, body;
    int http_status;
    int code;
    std::string message;  // a substring of the answer's message (JSON-escaped)
  };
  const auto escaped = [](const std::string& message) {
    // The message as the answer's JSON spells it (quotes escaped).
    google::protobuf::Value value;
    value.set_string_value(message);
    const std::string json = Json(value);
    return json.substr(1, json.size() - 2);
  };
  const std::vector<Row> rows = {
      {"POST", "/v1/maps/lab:predict", "{bad", 400, 3, "request body: "},
      {"POST", "/v1/maps", R"({"map": {"nmae": "x"}})", 400, 3, "request body: "},
      {"POST", "/v1/maps", R"({"map": {"name": "kindless"}})", 400, 3, escaped(no_kind)},
      {"GET", "/v1/maps/lab/region?hi.x=1&hi.y=1&foo=1", "", 400, 3, "unknown query parameter: foo"},
      {"GET", "/v1/maps/lab/region?lo.x=abc", "", 400, 3, "query parameter lo.x: not an integer: abc"},
      {"GET", "/v1/maps/lab/region?hi.x=99&hi.y=1", "", 400, 11, "hi.x"},
      {"GET", "/v1/maps/nope", "", 404, 5, escaped(unknown_map)},
      {"GET", "/v1/maps/rooms/region?hi.x=1&hi.y=1", "", 400, 9, escaped(grid_only)},
      {"GET", "/v1/maps/rooms/region.png?hi.x=1&hi.y=1", "", 400, 9, escaped(grid_only)},
      {"GET", "/v1/maps/lab/region.png?hi.x=1&hi.y=1&mode=heat", "", 400, 3, "query parameter mode"},
      {"GET", "/v1/maps/lab/writers/abc/lastSequence", "", 400, 3, "path variable writer_id: not an integer: abc"},
      {"GET", "/v1/nothing", "", 404, 5, "no route /v1/nothing"},
      {"GET", "/v1/maps/lab/bogus", "", 404, 5, "no route /v1/maps/lab/bogus"},
      {"DELETE", "/v1/status", "", 405, 12, "DELETE is not a method of /v1/status; it allows GET"},
      {"PUT", "/v1/maps/lab", "{}", 405, 12, "it allows DELETE, GET"},
      {"PATCH", "/v1/maps/lab", "{}", 405, 12, "it allows DELETE, GET"},
      {"GET", "/v1/maps/lab:predict", "", 405, 12, "it allows POST"},
  };
  for (const Row& row : rows) {
    const Answer answer = Call(row.method, row.path, row.body);
    SCOPED_TRACE(row.method + " " + row.path + " → " + answer.body);
    EXPECT_EQ(answer.status, row.http_status);
    EXPECT_EQ(answer.content_type, "application/json");
    const auto status = Parse<google::protobuf::Struct>(answer);
    ASSERT_TRUE(status.fields().contains("code"));
    EXPECT_EQ(status.fields().at("code").number_value(), row.code);
    EXPECT_TRUE(status.fields().at("details").has_list_value());
    EXPECT_THAT(answer.body, HasSubstr(row.message));
    if (row.http_status == 405) {
      EXPECT_FALSE(answer.allow.empty());
    }
  }
}

TEST_F(HttpApiTest, ABoxTooBigForOneAnswerIsResourceExhausted) {
  CreateOverHttp(GridMapSpec("big", 4100, 4100, 0.05));  // 16 810 000 cells > 16 Mi
  const Answer answer = Call("GET", "/v1/maps/big/region?hi.x=4100&hi.y=4100&output=REGION_OUTPUT_UINT8");
  EXPECT_EQ(answer.status, 429) << answer.body;
  EXPECT_THAT(answer.body, HasSubstr("\"code\":8"));
  EXPECT_THAT(answer.body, HasSubstr("the box [lo, hi) has 16810000 cells"));
  // The daemon is not left computing it: the next call is answered.
  Ok<v1::GetMapResponse>("GET", "/v1/maps/big");
}

// What `curl -X POST URL` sends: no body and no Content-Length, over a raw socket (httplib's client
// always sends a length).
std::string RawPostWithoutLength(const std::string& address, const std::string& path) {
  const HostPort split = SplitHostPort(address);
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(split.port));
  inet_pton(AF_INET, split.host.c_str(), &to.sin_addr);
  EXPECT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof(to)), 0);
  const std::string request = "POST " + path + " HTTP/1.1\r\nHost: fremend\r\n\r\n";
  EXPECT_EQ(write(fd, request.data(), request.size()), static_cast<ssize_t>(request.size()));
  // The answer: its headers, then Content-Length bytes (the connection stays open).
  std::string answer;
  char buffer[4096];
  for (ssize_t n; (n = read(fd, buffer, sizeof(buffer))) > 0;) {
    answer.append(buffer, static_cast<size_t>(n));
    const size_t end = answer.find("\r\n\r\n");
    const size_t length = answer.find("Content-Length: ");
    if (end == std::string::npos || length == std::string::npos) continue;
    if (answer.size() >= end + 4 + std::stoul(answer.substr(length + 16))) break;
  }
  close(fd);
  return answer;
}

TEST_F(HttpApiTest, AnEmptyPostBodyIsTheEmptyRequestAndNoBodyAtAllAStatus) {
  CreateOverHttp(GridMapSpec("lab", kWidth, kHeight, 0.5));
  httplib::Client client = HttpClientFor(daemon_->http_address());
  const httplib::Result empty = client.Post("/v1/maps/lab:check", "", "application/json");  // Content-Length: 0
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->status, 200) << empty->body;
  EXPECT_THAT(empty->body, HasSubstr("\"clean\":true"));
  const std::string raw = RawPostWithoutLength(daemon_->http_address(), "/v1/maps/lab:check");
  EXPECT_THAT(raw, HasSubstr("HTTP/1.1 411"));  // at once, not after httplib's read timeout
  EXPECT_THAT(raw, HasSubstr("\"code\":3"));
  EXPECT_THAT(raw, HasSubstr("a POST needs a body (at least {}) or Content-Length: 0"));
}

class HttpApiTokenTest : public HttpApiTest {
 protected:
  void SetUp() override {
    const std::string tokens = dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n");
    StartDaemon({"--tokens-file", tokens});
  }
  const httplib::Headers reader_ = {{"Authorization", "Bearer reader-token"}};
  const httplib::Headers writer_ = {{"Authorization", "Bearer writer-token"}};
};

TEST_F(HttpApiTokenTest, ReadTokensViewWriteTokensAct) {
  v1::CreateMapRequest create;
  *create.mutable_map() = GridMapSpec("lab", kWidth, kHeight, 0.5);
  EXPECT_EQ(Call("POST", "/v1/maps", Json(create), reader_).status, 403);
  Ok<v1::CreateMapResponse>("POST", "/v1/maps", Json(create), writer_);

  const Answer none = Call("GET", "/v1/maps");
  EXPECT_EQ(none.status, 401);
  EXPECT_THAT(none.body, HasSubstr("\"code\":16"));
  EXPECT_EQ(Call("GET", "/v1/maps", "", {{"Authorization", "Bearer not-a-token"}}).status, 401);
  EXPECT_EQ(Call("GET", "/v1/maps", "", {{"Authorization", "reader-token"}}).status, 401);  // no Bearer scheme
  Ok<v1::ListMapsResponse>("GET", "/v1/maps", "", reader_);
  Ok<v1::GetMapResponse>("GET", "/v1/maps/lab", "", reader_);
  EXPECT_EQ(Call("GET", "/v1/maps/lab/region.png?hi.x=2&hi.y=2", "", reader_).status, 200);
  Ok<v1::GetServerStatusResponse>("GET", "/v1/status", "", writer_);

  // The read token's refusal is gRPC's own.
  const std::string denied = GrpcMessage(grpc::StatusCode::PERMISSION_DENIED, [&] {
    v1::RunUpdateRequest run;
    run.set_map("lab");
    v1::Operation ignored;
    return admin()->RunUpdate(CallContext({{"authorization", "Bearer reader-token"}}).get(), run, &ignored);
  });
  const Answer run_read = Call("POST", "/v1/maps/lab:runUpdate", "{}", reader_);
  EXPECT_EQ(run_read.status, 403);
  EXPECT_THAT(run_read.body, HasSubstr("\"code\":7"));
  EXPECT_THAT(run_read.body, HasSubstr(denied));
  v1::IngestRequest batch;
  batch.set_writer_id(1);
  batch.set_sequence(1);
  batch.set_time(kT0);
  batch.mutable_cells()->mutable_cells()->add_x(1);
  batch.mutable_cells()->mutable_cells()->add_y(1);
  batch.mutable_cells()->add_values(1.0f);
  EXPECT_EQ(Call("POST", "/v1/maps/lab:ingest", Json(batch), reader_).status, 403);
  EXPECT_EQ(Call("DELETE", "/v1/maps/lab", "", reader_).status, 403);

  EXPECT_EQ(Ok<v1::IngestResponse>("POST", "/v1/maps/lab:ingest", Json(batch), writer_).accepted(), 1u);
  EXPECT_EQ(Ok<v1::Operation>("POST", "/v1/maps/lab:runUpdate", "{}", writer_).map(), "lab");
}

}  // namespace
}  // namespace fremen::testing
