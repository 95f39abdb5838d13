#include "server/gateway/route_pattern.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace fremen::server {
namespace {

using ::testing::Optional;
using ::testing::Pair;
using ::testing::UnorderedElementsAre;

TEST(RoutePatternTest, LiteralsMatchOnlyThemselves) {
  const RoutePattern pattern("/v1/maps");
  EXPECT_THAT(pattern.Match("/v1/maps"), Optional(PathVariables{}));
  EXPECT_EQ(pattern.Match("/v1/maps/"), std::nullopt);
  EXPECT_EQ(pattern.Match("/v1/map"), std::nullopt);
  EXPECT_EQ(pattern.Match("/v1"), std::nullopt);
  EXPECT_EQ(pattern.Match("v1/maps"), std::nullopt);
}

TEST(RoutePatternTest, VariablesCaptureOneSegmentEach) {
  const RoutePattern pattern("/v1/maps/{map}/writers/{writer_id}/lastSequence");
  auto variables = pattern.Match("/v1/maps/lab-2.b_c/writers/7/lastSequence");
  ASSERT_TRUE(variables);
  EXPECT_THAT(*variables, UnorderedElementsAre(Pair("map", "lab-2.b_c"), Pair("writer_id", "7")));
  EXPECT_EQ(pattern.Match("/v1/maps//writers/7/lastSequence"), std::nullopt);  // empty variable
  EXPECT_EQ(pattern.Match("/v1/maps/lab/writers/7"), std::nullopt);
}

TEST(RoutePatternTest, CapturedSegmentsAreUrlDecoded) {
  const RoutePattern pattern("/v1/maps/{map}");
  EXPECT_THAT(pattern.Match("/v1/maps/a%2Fb%20c"), Optional(PathVariables{{"map", "a/b c"}}));
  EXPECT_THAT(pattern.Match("/v1/maps/a+b"), Optional(PathVariables{{"map", "a+b"}}));  // '+' is no space in a path
}

TEST(RoutePatternTest, CustomVerbsAreTheirOwnRoutes) {
  const RoutePattern get("/v1/maps/{map}");
  const RoutePattern predict("/v1/maps/{map}:predict");
  EXPECT_EQ(get.Match("/v1/maps/lab:predict"), std::nullopt);  // not a map named "lab:predict"
  EXPECT_THAT(predict.Match("/v1/maps/lab:predict"), Optional(PathVariables{{"map", "lab"}}));
  EXPECT_EQ(predict.Match("/v1/maps/lab"), std::nullopt);
  EXPECT_EQ(predict.Match("/v1/maps/lab:predictx"), std::nullopt);
  EXPECT_EQ(predict.Match("/v1/maps/lab:check"), std::nullopt);
}

TEST(RoutePatternTest, AVariableMayHoldLiteralSegments) {
  const RoutePattern get("/v1/maps/{map}/{name=operations/*}");
  const RoutePattern cancel("/v1/maps/{map}/{name=operations/*}:cancel");
  EXPECT_THAT(get.Match("/v1/maps/lab/operations/update-lab-3"),
              Optional(PathVariables{{"map", "lab"}, {"name", "operations/update-lab-3"}}));
  EXPECT_EQ(get.Match("/v1/maps/lab/jobs/update-lab-3"), std::nullopt);
  EXPECT_EQ(get.Match("/v1/maps/lab/operations"), std::nullopt);
  EXPECT_EQ(get.Match("/v1/maps/lab/operations/update-lab-3:cancel"), std::nullopt);
  EXPECT_THAT(cancel.Match("/v1/maps/lab/operations/update-lab-3:cancel"),
              Optional(PathVariables{{"map", "lab"}, {"name", "operations/update-lab-3"}}));
  EXPECT_EQ(cancel.text(), "/v1/maps/{map}/{name=operations/*}:cancel");
}

TEST(RoutePatternTest, ADottedLiteralIsNoVerb) {
  const RoutePattern png("/v1/maps/{map}/region.png");
  EXPECT_THAT(png.Match("/v1/maps/lab/region.png"), Optional(PathVariables{{"map", "lab"}}));
  EXPECT_EQ(png.Match("/v1/maps/lab/region"), std::nullopt);
}

}  // namespace
}  // namespace fremen::server
