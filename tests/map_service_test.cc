// End-to-end tests of fremen.v1.MapService against the real fremend: every RPC, the bad-input rows
// that apply to maps (each with its exact status code and the field named), the x-fremen-map
// header, and maps surviving a restart.
#include <gmock/gmock.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <regex>

#include "fremen/v1/maps.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;
using Metadata = std::vector<std::pair<std::string, std::string>>;

v1::Map GridMap(const std::string& name) { return GridMapSpec(name, 400, 300, 0.05); }

v1::Map GenericMap(const std::string& name) { return GenericMapSpec(name); }

class MapServiceTest : public DaemonTest {
 protected:
  void SetUp() override {
    DaemonTest::SetUp();
    if (!HasFatalFailure()) Connect();
  }
  void Connect() { stub_ = v1::MapService::NewStub(daemon_->NewChannel()); }
  void Restart() {
    StopDaemon();
    StartDaemon();
    Connect();
  }

  grpc::Status Create(const v1::Map& map, v1::Map* created = nullptr, const Metadata& metadata = {}) {
    v1::CreateMapRequest request;
    *request.mutable_map() = map;
    v1::CreateMapResponse response;
    const grpc::Status status = stub_->CreateMap(CallContext(metadata).get(), request, &response);
    if (created != nullptr) *created = response.map();
    return status;
  }
  grpc::Status Get(const std::string& name, v1::Map* map = nullptr, const Metadata& metadata = {}) {
    v1::GetMapRequest request;
    request.set_map(name);
    v1::GetMapResponse response;
    const grpc::Status status = stub_->GetMap(CallContext(metadata).get(), request, &response);
    if (map != nullptr) *map = response.map();
    return status;
  }
  grpc::Status List(int page_size, const std::string& token, v1::ListMapsResponse* response) {
    v1::ListMapsRequest request;
    request.set_page_size(page_size);
    request.set_page_token(token);
    return stub_->ListMaps(CallContext().get(), request, response);
  }
  grpc::Status Delete(const std::string& name) {
    v1::DeleteMapRequest request;
    request.set_map(name);
    v1::DeleteMapResponse response;
    return stub_->DeleteMap(CallContext().get(), request, &response);
  }
  // Every map's name, page by page.
  std::vector<std::string> ListAllNames(int page_size) {
    std::vector<std::string> names;
    std::string token;
    do {
      v1::ListMapsResponse response;
      const grpc::Status status = List(page_size, token, &response);
      EXPECT_TRUE(status.ok()) << status.error_message();
      if (!status.ok()) break;
      for (const v1::Map& map : response.maps()) names.push_back(map.name());
      token = response.next_page_token();
    } while (!token.empty());
    return names;
  }

  std::unique_ptr<v1::MapService::Stub> stub_;
};

TEST_F(MapServiceTest, CreateMapFillsInTheDefaults) {
  v1::Map created;
  const grpc::Status status = Create(GridMap("lab"), &created);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(created.name(), "lab");
  EXPECT_EQ(created.kind(), v1::MAP_KIND_GRID);
  EXPECT_EQ(created.grid().resolution(), 0.05);
  EXPECT_EQ(created.grid().size().x(), 400u);
  EXPECT_EQ(created.grid().size().y(), 300u);
  EXPECT_EQ(created.grid().size().z(), 1u);  // unset z: a 2-D grid
  EXPECT_EQ(created.periods().longest_seconds(), 604800);
  EXPECT_EQ(created.periods().count(), 24u);
  EXPECT_TRUE(created.has_max_order());
  EXPECT_EQ(created.max_order(), 5u);
  EXPECT_TRUE(created.persistence());
  EXPECT_EQ(created.error_half_life_seconds(), 7 * 86400);
  EXPECT_EQ(created.criterion(), v1::ERROR_CRITERION_THRESHOLD);
  EXPECT_EQ(created.order_selection(), v1::ORDER_SELECTION_MARGIN);
  EXPECT_EQ(created.order_margin(), 0.001);
  EXPECT_EQ(created.order_temperature(), 0.01);
  EXPECT_EQ(created.lossless_sampling_seconds(), 0);
  EXPECT_GE(created.shards(), 1u);
  EXPECT_GT(created.create_time().seconds(), 1600000000);
}

TEST_F(MapServiceTest, CreateMapKeepsEverySetting) {
  v1::Map map = GenericMap("doors");
  map.mutable_periods()->add_explicit_seconds(86400);
  map.mutable_periods()->add_explicit_seconds(3600);
  map.set_max_order(2);
  map.set_persistence(false);
  map.set_error_half_life_seconds(0);
  map.set_criterion(v1::ERROR_CRITERION_SQUARED);
  map.set_lossless_sampling_seconds(60);
  map.set_lossless_origin(1.7e9);
  map.set_shards(2);
  v1::Map created;
  const grpc::Status status = Create(map, &created);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_FALSE(created.has_grid());
  EXPECT_THAT(created.periods().explicit_seconds(), ::testing::ElementsAre(86400, 3600));
  EXPECT_EQ(created.max_order(), 2u);
  EXPECT_FALSE(created.persistence());
  EXPECT_EQ(created.error_half_life_seconds(), 0);
  EXPECT_EQ(created.criterion(), v1::ERROR_CRITERION_SQUARED);
  EXPECT_EQ(created.lossless_sampling_seconds(), 60);
  EXPECT_EQ(created.lossless_origin(), 1.7e9);
  EXPECT_EQ(created.shards(), 2u);
}

TEST_F(MapServiceTest, GetMapAnswersWhatCreateMapMade) {
  v1::Map created, got;
  ASSERT_TRUE(Create(GridMap("lab"), &created).ok());
  const grpc::Status status = Get("lab", &got);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_TRUE(MessageDifferencer::Equals(created, got)) << created.DebugString() << got.DebugString();
}

TEST_F(MapServiceTest, ListMapsPagesInNameOrder) {
  for (const char* name : {"e", "a", "d", "c", "b"}) ASSERT_TRUE(Create(GenericMap(name)).ok());
  EXPECT_THAT(ListAllNames(2), ::testing::ElementsAre("a", "b", "c", "d", "e"));
  EXPECT_THAT(ListAllNames(0), ::testing::ElementsAre("a", "b", "c", "d", "e"));  // the default page
  v1::ListMapsResponse first;
  ASSERT_TRUE(List(2, "", &first).ok());
  EXPECT_EQ(first.maps_size(), 2);
  EXPECT_FALSE(first.next_page_token().empty());
  v1::ListMapsResponse all;
  ASSERT_TRUE(List(1000, "", &all).ok());
  EXPECT_EQ(all.maps_size(), 5);
  EXPECT_TRUE(all.next_page_token().empty());
}

TEST_F(MapServiceTest, ListMapsOnAnEmptyDaemon) {
  v1::ListMapsResponse response;
  ASSERT_TRUE(List(0, "", &response).ok());
  EXPECT_EQ(response.maps_size(), 0);
  EXPECT_TRUE(response.next_page_token().empty());
}

TEST_F(MapServiceTest, ListMapsPageSizeRules) {
  v1::ListMapsResponse response;
  const grpc::Status negative = List(-1, "", &response);
  EXPECT_EQ(negative.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(negative.error_message(), HasSubstr("page_size"));
  // Above the maximum is taken as the maximum (Google's API guidelines).
  EXPECT_TRUE(List(1 << 30, "", &response).ok());
}

TEST_F(MapServiceTest, BadPageTokenIsInvalidArgument) {
  v1::ListMapsResponse response;
  const grpc::Status status = List(10, "not-a-token", &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("page_token"));
}

TEST_F(MapServiceTest, DeleteMapRemovesTheMap) {
  ASSERT_TRUE(Create(GridMap("lab")).ok());
  ASSERT_TRUE(Create(GridMap("office")).ok());
  const grpc::Status status = Delete("lab");
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(Get("lab").error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(ListAllNames(10), ::testing::ElementsAre("office"));
  // The name is free again.
  EXPECT_TRUE(Create(GenericMap("lab")).ok());
}

TEST_F(MapServiceTest, DuplicateNameIsAlreadyExists) {
  ASSERT_TRUE(Create(GridMap("lab")).ok());
  const grpc::Status status = Create(GenericMap("lab"));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::ALREADY_EXISTS);
  EXPECT_THAT(status.error_message(), HasSubstr("lab"));
}

TEST_F(MapServiceTest, UnknownMapIsNotFound) {
  const grpc::Status get = Get("nowhere");
  EXPECT_EQ(get.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(get.error_message(), HasSubstr("nowhere"));
  EXPECT_EQ(Delete("nowhere").error_code(), grpc::StatusCode::NOT_FOUND);
}

// Each row: a bad map, and the field its INVALID_ARGUMENT must name. The daemon serves on after all.
TEST_F(MapServiceTest, BadFieldsAreInvalidArgumentNamingTheField) {
  struct Row {
    std::string field;
    std::function<void(v1::Map&)> spoil;
  };
  const std::vector<Row> rows = {
      {"map.name is required", [](v1::Map& m) { m.set_name(""); }},
      {"map.name may hold only", [](v1::Map& m) { m.set_name("two words"); }},
      {"map.name must be 1 to 128", [](v1::Map& m) { m.set_name(std::string(129, 'a')); }},
      {"map.name must be", [](v1::Map& m) { m.set_name(".hidden"); }},
      {"map.kind is required", [](v1::Map& m) { m.set_kind(v1::MAP_KIND_UNSPECIFIED); }},
      {"map.grid is required", [](v1::Map& m) { m.clear_grid(); }},
      {"map.grid.resolution", [](v1::Map& m) { m.mutable_grid()->set_resolution(0); }},
      {"map.grid.resolution", [](v1::Map& m) { m.mutable_grid()->set_resolution(-0.05); }},
      {"map.grid.resolution", [](v1::Map& m) { m.mutable_grid()->set_resolution(NAN); }},
      {"map.grid.origin.x", [](v1::Map& m) { m.mutable_grid()->mutable_origin()->set_x(INFINITY); }},
      {"map.grid.size.x", [](v1::Map& m) { m.mutable_grid()->mutable_size()->set_x(0); }},
      {"map.grid.size.y", [](v1::Map& m) { m.mutable_grid()->mutable_size()->set_y(3000000); }},
      {"map.periods.longest_seconds", [](v1::Map& m) { m.mutable_periods()->set_longest_seconds(-1); }},
      {"map.periods.count", [](v1::Map& m) { m.mutable_periods()->set_count(0); }},
      {"map.periods.explicit_seconds[0]", [](v1::Map& m) { m.mutable_periods()->add_explicit_seconds(NAN); }},
      {"map.max_order", [](v1::Map& m) { m.set_max_order(65); }},
      {"map.error_half_life_seconds", [](v1::Map& m) { m.set_error_half_life_seconds(-1); }},
      {"map.criterion", [](v1::Map& m) { m.set_criterion(static_cast<v1::ErrorCriterion>(42)); }},
      {"map.lossless_sampling_seconds", [](v1::Map& m) { m.set_lossless_sampling_seconds(-1); }},
      {"map.shards", [](v1::Map& m) { m.set_shards(300); }},
  };
  for (const Row& row : rows) {
    v1::Map map = GridMap("lab");
    row.spoil(map);
    const grpc::Status status = Create(map);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << row.field;
    EXPECT_THAT(status.error_message(), HasSubstr(row.field));
  }
  v1::Map generic_with_grid = GenericMap("doors");
  *generic_with_grid.mutable_grid() = GridMap("x").grid();
  EXPECT_THAT(Create(generic_with_grid).error_message(), HasSubstr("map.grid must be unset"));

  EXPECT_EQ(Get("").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(ListAllNames(10), ::testing::IsEmpty());  // nothing was created, and the daemon serves on
}

TEST_F(MapServiceTest, TheMapHeaderMayNameTheMap) {
  // Through a proxy, the header carries the name; the field may then be left empty.
  v1::Map nameless = GridMap("");
  ASSERT_TRUE(Create(nameless, nullptr, {{"x-fremen-map", "lab"}}).ok());
  v1::Map got;
  ASSERT_TRUE(Get("", &got, {{"x-fremen-map", "lab"}}).ok());
  EXPECT_EQ(got.name(), "lab");
  ASSERT_TRUE(Get("lab", &got, {{"x-fremen-map", "lab"}}).ok());
}

TEST_F(MapServiceTest, HeaderAndFieldMustAgree) {
  ASSERT_TRUE(Create(GridMap("lab")).ok());
  const grpc::Status get = Get("lab", nullptr, {{"x-fremen-map", "office"}});
  EXPECT_EQ(get.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(get.error_message(), HasSubstr("x-fremen-map"));
  const grpc::Status create = Create(GridMap("office"), nullptr, {{"x-fremen-map", "lab"}});
  EXPECT_EQ(create.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(create.error_message(), HasSubstr("map.name"));
}

TEST_F(MapServiceTest, RestartKeepsMaps) {
  v1::Map lab, doors;
  ASSERT_TRUE(Create(GridMap("lab"), &lab).ok());
  ASSERT_TRUE(Create(GenericMap("doors"), &doors).ok());
  ASSERT_TRUE(Create(GenericMap("gone")).ok());
  ASSERT_TRUE(Delete("gone").ok());
  Restart();
  ASSERT_FALSE(HasFatalFailure());
  v1::Map got;
  ASSERT_TRUE(Get("lab", &got).ok());
  EXPECT_TRUE(MessageDifferencer::Equals(lab, got)) << lab.DebugString() << got.DebugString();
  ASSERT_TRUE(Get("doors", &got).ok());
  EXPECT_TRUE(MessageDifferencer::Equals(doors, got));
  EXPECT_THAT(ListAllNames(10), ::testing::ElementsAre("doors", "lab"));
}

TEST_F(MapServiceTest, EveryCallHasAnAccessLogLine) {
  ASSERT_TRUE(Create(GridMap("lab")).ok());
  ASSERT_EQ(Get("nowhere").error_code(), grpc::StatusCode::NOT_FOUND);
  const std::string log = daemon_->Log();
  EXPECT_TRUE(std::regex_search(log, std::regex(R"(\[access\] CreateMap ipv4:127\.0\.0\.1:\d+ OK [0-9.]+ms)"))) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex(R"(\[access\] GetMap ipv4:127\.0\.0\.1:\d+ NOT_FOUND [0-9.]+ms .*nowhere)")))
      << log;
}

}  // namespace
}  // namespace fremen::testing
