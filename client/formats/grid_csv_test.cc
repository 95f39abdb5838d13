#include "client/formats/grid_csv.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

namespace fremen::formats {
namespace {

using ::testing::HasSubstr;

absl::StatusOr<std::vector<CellObservation>> Parse(const std::string& text) {
  std::istringstream in(text);
  return ReadGridCsv(in, "grid.csv");
}

TEST(GridCsvTest, ReadsTwoDimensionalRowsWithHeaderAndComments) {
  absl::StatusOr<std::vector<CellObservation>> rows =
      Parse("time,x,y,state\n# scan 1\n100,1,2,1\n\n100, 3 ,4,0.25\r\n");
  ASSERT_TRUE(rows.ok()) << rows.status();
  ASSERT_EQ(rows->size(), 2u);
  EXPECT_EQ((*rows)[1].t, 100);
  EXPECT_EQ((*rows)[1].x, 3u);
  EXPECT_EQ((*rows)[1].y, 4u);
  EXPECT_EQ((*rows)[1].z, 0u);
  EXPECT_FLOAT_EQ((*rows)[1].s, 0.25f);
}

TEST(GridCsvTest, ReadsThreeDimensionalRowsWithoutHeader) {
  absl::StatusOr<std::vector<CellObservation>> rows = Parse("1.5,1,2,3,1\n2.5,4,5,6,0\n");
  ASSERT_TRUE(rows.ok()) << rows.status();
  ASSERT_EQ(rows->size(), 2u);
  EXPECT_EQ((*rows)[0].z, 3u);
  EXPECT_EQ((*rows)[1].t, 2.5);
}

TEST(GridCsvTest, ErrorsNameFileLineAndField) {
  EXPECT_EQ(Parse("time,x,y,state\n1,-1,2,1\n").status().message(),
            "grid.csv:2: field x: expected a cell index (an integer in [0, 4294967295]), got \"-1\"");
  EXPECT_EQ(Parse("1,1,2,1.5\n").status().message(),
            "grid.csv:1: field state: expected a number in [0, 1], got \"1.5\"");
  EXPECT_THAT(Parse("nan,1,2,1\n").status().message(), HasSubstr("grid.csv:1: field time"));
  EXPECT_THAT(Parse("1,1,2,z,1\n").status().message(), HasSubstr("grid.csv:1: field z"));
  EXPECT_THAT(Parse("1,1,2\n").status().message(), HasSubstr("grid.csv:1: expected 4 fields"));
  EXPECT_THAT(Parse("1,1,2,1\n2,1,2,3,1\n").status().message(),
              HasSubstr("grid.csv:2: expected 4 fields as on the lines before"));
  EXPECT_THAT(Parse("time,x,y,state\n2,1,2,3,1\n").status().message(), HasSubstr("grid.csv:2: expected 4 fields"));
  EXPECT_THAT(Parse("time,y,x,state\n").status().message(), HasSubstr("grid.csv:1: the header must be"));
  EXPECT_EQ(Parse("# nothing\n").status().message(), "grid.csv: no observations");
  EXPECT_THAT(ReadGridCsv("/nonexistent/g.csv").status().message(), HasSubstr("/nonexistent/g.csv: cannot open"));
}

TEST(ObservationBatchesTest, GroupsByTimeInTimeOrder) {
  const std::vector<CellObservation> rows = {{20, 1, 1, 0, 1}, {10, 2, 2, 0, 0}, {20, 3, 3, 0, 0.5f}, {10, 4, 4, 1, 1}};
  const std::vector<CellBatch> batches = GroupByTime(rows);
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_EQ(batches[0].time, 10);
  EXPECT_EQ(batches[0].x, (std::vector<uint32_t>{2, 4}));
  EXPECT_EQ(batches[0].z, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(batches[1].time, 20);
  EXPECT_EQ(batches[1].values, (std::vector<float>{1, 0.5f}));
}

}  // namespace
}  // namespace fremen::formats
