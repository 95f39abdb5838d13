#include "client/fremenctl/cli_args.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "client/fremenctl/connection.h"

namespace fremen::client {
namespace {

using ::testing::HasSubstr;

TEST(CliArgsTest, TimesAreNowSecondsOrRfc3339) {
  const absl::Time now = absl::FromUnixSeconds(1700000000);
  EXPECT_DOUBLE_EQ(*ParseTimeArg("now", now), 1700000000);
  EXPECT_DOUBLE_EQ(*ParseTimeArg("1700000123.5", now), 1700000123.5);
  EXPECT_DOUBLE_EQ(*ParseTimeArg("2023-11-14T22:13:20Z", now), 1700000000);
  EXPECT_DOUBLE_EQ(*ParseTimeArg("2023-11-14T23:13:20+01:00", now), 1700000000);
  auto bad = ParseTimeArg("tomorrow", now);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("\"tomorrow\" is not \"now\", seconds since 1970, or RFC 3339"));
  EXPECT_FALSE(ParseTimeArg("nan", now).ok());
}

TEST(CliArgsTest, CellsAreTwoOrThreeWholeIndices) {
  EXPECT_EQ(*ParseCellArg("3,4"), (Cell{3, 4, 0}));
  EXPECT_EQ(*ParseCellArg("3,4,5"), (Cell{3, 4, 5}));
  for (const char* bad : {"3", "3,4,5,6", "-1,2", "1.5,2", "a,b", ""}) {
    auto cell = ParseCellArg(bad);
    EXPECT_FALSE(cell.ok()) << bad;
    EXPECT_THAT(cell.status().message(), HasSubstr("is not X,Y or X,Y,Z")) << bad;
  }
}

TEST(CliArgsTest, PointsAreTwoOrThreeMetricCoordinates) {
  auto p = ParsePointArg("1.5,-2");
  ASSERT_TRUE(p.ok());
  EXPECT_DOUBLE_EQ(p->x, 1.5);
  EXPECT_DOUBLE_EQ(p->y, -2);
  EXPECT_DOUBLE_EQ(p->z, 0);
  EXPECT_FALSE(ParsePointArg("1,inf").ok());
}

TEST(CliArgsTest, StatesAreOfOneKind) {
  StateArgs cells;
  cells.cells = {"1,2", "3,4,1"};
  auto set = ParseStateArgs(cells);
  ASSERT_TRUE(set.ok()) << set.status();
  EXPECT_EQ(set->size(), 2u);
  EXPECT_EQ(set->proto().cells().z(1), 1u);
  StateArgs ids;
  ids.ids = {7};
  EXPECT_EQ(ParseStateArgs(ids)->proto().ids(0), 7u);
  StateArgs mixed = cells;
  mixed.names = {"door"};
  EXPECT_THAT(ParseStateArgs(mixed).status().message(), HasSubstr("cannot be mixed"));
  EXPECT_FALSE(ParseStateArgs(StateArgs{}).ok());
  StateArgs bad;
  bad.points = {"1"};
  EXPECT_THAT(ParseStateArgs(bad).status().message(), HasSubstr("point \"1\""));
}

TEST(CliArgsTest, TimesAreAllParsed) {
  auto times = ParseTimeArgs({"10", "now"}, absl::FromUnixSeconds(20));
  ASSERT_TRUE(times.ok());
  EXPECT_THAT(*times, ::testing::ElementsAre(10, 20));
  EXPECT_FALSE(ParseTimeArgs({}).ok());
  EXPECT_FALSE(ParseTimeArgs({"10", "soon"}).ok());
}

TEST(CliArgsTest, HintsSayWhatToFix) {
  EXPECT_THAT(HintFor(absl::NotFoundError("no map named \"x\""), "x", "h:1"), HasSubstr("fremenctl maps list"));
  EXPECT_EQ(HintFor(absl::NotFoundError("no operation named \"o\""), "x", "h:1"), "");
  EXPECT_THAT(HintFor(absl::UnavailableError("down"), "", "h:1"), HasSubstr("is fremend running at h:1"));
  EXPECT_THAT(HintFor(absl::UnauthenticatedError("no"), "", "h:1"), HasSubstr("--token"));
  EXPECT_THAT(HintFor(absl::PermissionDeniedError("no"), "", "h:1"), HasSubstr("write token"));
  EXPECT_THAT(HintFor(absl::DeadlineExceededError("slow"), "", "h:1"), HasSubstr("--timeout"));
}

}  // namespace
}  // namespace fremen::client
