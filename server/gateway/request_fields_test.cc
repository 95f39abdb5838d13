#include "server/gateway/request_fields.h"

#include "fremen/v1/ingest.pb.h"
#include "fremen/v1/query.pb.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using Params = std::multimap<std::string, std::string>;

absl::Status Fails(const Params& params, google::protobuf::Message&& message) {
  return SetFieldsFromQuery(params, message);
}

TEST(RequestFieldsTest, SetsScalarsNestedMessagesAndEnums) {
  v1::PredictRegionRequest request;
  ASSERT_TRUE(SetFieldsFromQuery({{"map", "lab"},
                                  {"lo.x", "1"},
                                  {"lo.y", "2"},
                                  {"hi.x", "64"},
                                  {"hi.y", "48"},
                                  {"time", "1.7e9"},
                                  {"output", "REGION_OUTPUT_UINT8"},
                                  {"confidence", "0.25"},
                                  {"options.persistence", "true"},
                                  {"options.order", "2"}},
                                 request)
                  .ok());
  EXPECT_EQ(request.map(), "lab");
  EXPECT_EQ(request.lo().x(), 1u);
  EXPECT_EQ(request.lo().y(), 2u);
  EXPECT_EQ(request.hi().x(), 64u);
  EXPECT_EQ(request.hi().y(), 48u);
  EXPECT_EQ(request.time(), 1.7e9);
  EXPECT_EQ(request.output(), v1::REGION_OUTPUT_UINT8);
  EXPECT_FLOAT_EQ(request.confidence(), 0.25f);
  EXPECT_TRUE(request.options().persistence());
  ASSERT_TRUE(request.options().has_order());  // an optional field set to its value, even 0
  EXPECT_EQ(request.options().order(), 2u);
}

TEST(RequestFieldsTest, EnumsByNumberAndCamelCaseNames) {
  v1::PredictRegionRequest request;
  ASSERT_TRUE(SetFieldsFromQuery({{"output", "4"}, {"chunkCells", "9"}}, request).ok());
  EXPECT_EQ(request.output(), v1::REGION_OUTPUT_STATES);
  EXPECT_EQ(request.chunk_cells(), 9u);
}

TEST(RequestFieldsTest, RepeatedFieldsByRepeatingTheParameterInOrder) {
  v1::PredictRequest request;
  ASSERT_TRUE(SetFieldsFromQuery({{"times", "3"}, {"times", "1"}, {"times", "2"}, {"states.names", "door"}}, request)
                  .ok());
  EXPECT_THAT(request.times(), ElementsAre(3.0, 1.0, 2.0));
  EXPECT_THAT(request.states().names(), ElementsAre("door"));
}

TEST(RequestFieldsTest, OneofMembersAnd64BitIntegers) {
  v1::GetStateModelRequest model;
  ASSERT_TRUE(SetFieldsFromQuery({{"state.cell.x", "3"}, {"state.cell.y", "4"}}, model).ok());
  EXPECT_EQ(model.state().ref_case(), v1::StateRef::kCell);
  EXPECT_EQ(model.state().cell().y(), 4u);
  ASSERT_TRUE(SetFieldsFromQuery({{"state.id", "18446744073709551615"}}, model).ok());
  EXPECT_EQ(model.state().id(), UINT64_MAX);
  v1::LastSequenceRequest last;
  ASSERT_TRUE(SetField("writer_id", "9007199254740993", last).ok());  // beyond a double's exact integers
  EXPECT_EQ(last.writer_id(), 9007199254740993u);
}

TEST(RequestFieldsTest, BoolSpellings) {
  v1::GetStateModelRequest request;
  for (const auto& [text, value] : std::vector<std::pair<std::string, bool>>{
           {"true", true}, {"false", false}, {"1", true}, {"0", false}, {"TRUE", true}}) {
    ASSERT_TRUE(SetField("include_spectrum", text, request).ok()) << text;
    EXPECT_EQ(request.include_spectrum(), value) << text;
  }
}

TEST(RequestFieldsTest, ErrorsNameTheParameter) {
  struct Row {
    Params params;
    std::string message;
  };
  const std::vector<Row> rows = {
      {{{"foo", "1"}}, "unknown query parameter: foo"},
      {{{"lo.w", "1"}}, "unknown query parameter: lo.w"},
      {{{"time.x", "1"}}, "unknown query parameter: time.x (time has no fields)"},
      {{{"lo.x", "abc"}}, "query parameter lo.x: not an integer: abc"},
      {{{"lo.x", "-1"}}, "query parameter lo.x: out of range for uint32: -1"},
      {{{"lo.x", "4294967296"}}, "query parameter lo.x: out of range for uint32: 4294967296"},
      {{{"time", "soon"}}, "query parameter time: not a finite number: soon"},
      {{{"time", "nan"}}, "query parameter time: not a finite number: nan"},
      {{{"output", "PNG"}}, "query parameter output: not a value of fremen.v1.RegionOutput: PNG"},
      {{{"output", "99"}}, "query parameter output: not a value of fremen.v1.RegionOutput: 99"},
      {{{"options.persistence", "yes"}}, "query parameter options.persistence: not a bool (true, false, 1 or 0): yes"},
      {{{"lo", "1"}}, "query parameter lo: is a message; name one of its fields (lo.x)"},
      {{{"time", "1"}, {"time", "2"}}, "query parameter time: given 2 times but it is not repeated"},
  };
  for (const Row& row : rows) {
    const absl::Status status = Fails(row.params, v1::PredictRegionRequest());
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << row.message;
    EXPECT_EQ(status.message(), row.message);
  }
}

}  // namespace
}  // namespace fremen::server
