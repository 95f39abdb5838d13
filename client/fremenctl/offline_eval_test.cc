// Unit tests of the offline evaluation: the `time state` reader and the per-order scores.
#include "client/fremenctl/offline_eval.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

namespace fremen::client {
namespace {

using ::testing::HasSubstr;

absl::StatusOr<std::vector<model::Observation>> Read(const std::string& text) {
  std::istringstream in(text);
  return ReadObservations(in, "data.txt");
}

TEST(ReadObservationsTest, ReadsTimesAndStatesSkippingBlankAndCommentLines) {
  const auto observations = Read("# time state\n0 0\n\n60\t1\r\n  1700000000.5  0.25\n");
  ASSERT_TRUE(observations.ok()) << observations.status();
  ASSERT_EQ(observations->size(), 3u);
  EXPECT_EQ((*observations)[1].t, 60);
  EXPECT_EQ((*observations)[1].s, 1.0f);
  EXPECT_EQ((*observations)[2].t, 1700000000.5);
  EXPECT_EQ((*observations)[2].s, 0.25f);
}

struct BadInput {
  std::string name;  // of the test case
  std::string text;
  std::string message;  // expected in the error, after "data.txt:<line>: "
};

class ReadObservationsErrorTest : public ::testing::TestWithParam<BadInput> {};

TEST_P(ReadObservationsErrorTest, NamesFileAndLine) {
  const auto observations = Read(GetParam().text);
  ASSERT_FALSE(observations.ok());
  EXPECT_THAT(observations.status().message(), HasSubstr(GetParam().message));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ReadObservationsErrorTest,
    ::testing::Values(BadInput{"MissingState", "0 0\n60\n", "data.txt:2: expected `time state`"},
                      BadInput{"ExtraField", "0 0 1\n", "data.txt:1: expected `time state`"},
                      BadInput{"StateNotANumber", "0 0\n\n60 x\n", "data.txt:3: state is not a number"},
                      BadInput{"TimeNotANumber", "1O 0\n", "data.txt:1: time is not a number"},
                      BadInput{"StateAboveOne", "0 2.0\n", "data.txt:1: state must be in [0, 1]"},
                      BadInput{"StateBelowZero", "0 -0.1\n", "data.txt:1: state must be in [0, 1]"},
                      BadInput{"StateNaN", "0 nan\n", "data.txt:1: state must be in [0, 1]"},
                      BadInput{"TimeNaN", "nan 1\n", "data.txt:1: observation.t must be a finite time"},
                      BadInput{"TimeInfinite", "inf 1\n", "data.txt:1: observation.t must be a finite time"},
                      BadInput{"TimeAbsurd", "1e14 1\n", "data.txt:1: observation.t must be a finite time"},
                      BadInput{"NoObservations", "# only a comment\n", "data.txt: no observations"}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

TEST(ReadObservationsTest, MissingFileIsNamed) {
  const auto observations = ReadObservations("/nonexistent/train.txt");
  ASSERT_FALSE(observations.ok());
  EXPECT_THAT(observations.status().message(), HasSubstr("/nonexistent/train.txt"));
}

// A constant training signal has an all-zero spectrum, so p = the constant at every order.
std::vector<OrderScore> ScoresOfConstant(float trained, float tested) {
  std::vector<model::Observation> train, test;
  for (int i = 0; i < 2000; ++i) train.push_back({60.0 * i, trained});
  for (int i = 0; i < 100; ++i) test.push_back({120000.0 + 60.0 * i, tested});
  model::ModelSettings settings;
  settings.max_order = 3;
  return EvaluateOffline(settings, train, test, /*with_persistence=*/false);
}

TEST(EvaluateOfflineTest, ScoresEveryOrderFromZeroToL) {
  const std::vector<OrderScore> scores = ScoresOfConstant(1, 0);
  ASSERT_EQ(scores.size(), 4u);
  for (int order = 0; order <= 3; ++order) {
    EXPECT_EQ(scores[order].order, order);
    EXPECT_DOUBLE_EQ(scores[order].err, 1.0);
    EXPECT_DOUBLE_EQ(scores[order].mse, 1.0);
  }
}

TEST(EvaluateOfflineTest, SoftStatesCountTheProbabilityMassGotWrong) {
  // p = 0.3 estimates 0; a soft state 0.3 makes that wrong by 0.3, with no squared error.
  for (const OrderScore& score : ScoresOfConstant(0.3f, 0.3f)) {
    EXPECT_NEAR(score.err, 0.3, 1e-6);
    EXPECT_NEAR(score.mse, 0.0, 1e-12);
  }
}

}  // namespace
}  // namespace fremen::client
