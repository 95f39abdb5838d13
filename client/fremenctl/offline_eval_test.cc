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

// Three weeks of a door open 8:00-17:00 every day at 10-minute samples, some days flipped; the test
// is the clean week after. Fed day by day, every rule must find the daily component.
TEST(EvaluateReplayTest, EveryRuleFindsADailyDoorFedDayByDay) {
  std::vector<model::Observation> train, test;
  const auto door = [](double t) { return std::fmod(t, 86400.0) >= 8 * 3600 && std::fmod(t, 86400.0) < 17 * 3600; };
  for (double t = 0; t < 21 * 86400.0; t += 600) {
    const bool flipped = static_cast<int>(t / 86400) % 5 == 3;  // a day in five the other way round
    train.push_back({t, door(t) != flipped ? 1.0f : 0.0f});
  }
  for (double t = 21 * 86400.0; t < 28 * 86400.0; t += 600) test.push_back({t, door(t) ? 1.0f : 0.0f});
  for (const model::OrderSelection selection :
       {model::OrderSelection::kPaper, model::OrderSelection::kMargin, model::OrderSelection::kWeighted}) {
    model::ModelSettings settings;
    settings.order_rule.selection = selection;
    const OrderScore score = EvaluateReplay(settings, train, test);
    EXPECT_GE(score.order, 1) << static_cast<int>(selection);
    EXPECT_LT(score.err, 0.1) << static_cast<int>(selection);
    EXPECT_LT(score.mse, 0.1) << static_cast<int>(selection);
  }
}

// One day of data means one update before any scoring: order 0 whatever the rule, so the test is
// predicted by the mean.
TEST(EvaluateReplayTest, OneDayIsOrderZero) {
  std::vector<model::Observation> train, test;
  for (double t = 0; t < 86400; t += 60) train.push_back({t, t < 43200 ? 1.0f : 0.0f});
  test.push_back({90000, 1.0f});
  const OrderScore score = EvaluateReplay(model::ModelSettings{}, train, test);
  EXPECT_EQ(score.order, 0);
  EXPECT_NEAR(score.mse, 0.25, 1e-3);
}

}  // namespace
}  // namespace fremen::client
