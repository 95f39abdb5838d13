#include "server/convert/query_args.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

TEST(QueryArgsTest, TimesMustBeFiniteAndWithinRange) {
  EXPECT_TRUE(CheckTime(1.7e9, "time").ok());
  EXPECT_TRUE(CheckTime(0, "time").ok());
  EXPECT_TRUE(CheckTime(1e13, "time").ok());
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1.0001e13,
                     -1.0, -1e13}) {
    const absl::Status s = CheckTime(bad, "time");
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(s.message(), HasSubstr("time must be"));
  }
  const std::vector<double> times = {0, 1, -std::numeric_limits<double>::infinity()};
  const absl::Status s = CheckTimes(times, "times");
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("times[2] must be"));
}

TEST(QueryArgsTest, ConfidenceInItsRange) {
  EXPECT_TRUE(CheckConfidence(0.5f, 0.5f, 1, "confidence").ok());
  EXPECT_TRUE(CheckConfidence(1, 0, 1, "confidence").ok());
  for (float bad : {-0.1f, 1.1f, std::numeric_limits<float>::quiet_NaN()}) {
    const absl::Status s = CheckConfidence(bad, 0, 1, "confidence");
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(s.message(), HasSubstr("confidence must be in [0, 1]"));
  }
  EXPECT_EQ(CheckConfidence(0.4f, 0.5f, 1, "confidence").code(), absl::StatusCode::kInvalidArgument);
}

TEST(QueryArgsTest, PredictionCountIsCapped) {
  EXPECT_TRUE(CheckPredictionCount(kMaxPredictions, 1).ok());
  const absl::Status s = CheckPredictionCount(3000, 5000);
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(s.message(), HasSubstr("3000 × 5000 = 15000000"));
}

TEST(QueryArgsTest, OptionsAgainstTheMap) {
  storage::MapInfo map;
  map.name = "lab";
  map.max_order = 3;
  map.persistence = false;
  v1::PredictionOptions options;
  auto none = PredictOptionsOf(map, options, "options");
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->order, -1);
  EXPECT_FALSE(none->persistence);

  options.set_order(3);
  auto at_l = PredictOptionsOf(map, options, "options");
  ASSERT_TRUE(at_l.ok());
  EXPECT_EQ(at_l->order, 3);

  options.set_order(4);
  const absl::Status above = PredictOptionsOf(map, options, "options").status();
  EXPECT_EQ(above.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(above.message(), HasSubstr("options.order must be ≤ 3"));

  options.clear_order();
  options.set_persistence(true);
  const absl::Status persistence = PredictOptionsOf(map, options, "options").status();
  EXPECT_EQ(persistence.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(persistence.message(), HasSubstr("options.persistence"));
  map.persistence = true;
  EXPECT_TRUE(PredictOptionsOf(map, options, "options")->persistence);
}

}  // namespace
}  // namespace fremen::server
