#include "storage/model/order_selection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace fremen::model {
namespace {

// Rates r_l given as errors over a weight of 2, so that the rules must divide.
int Select(std::vector<double> rates, const OrderRule& rule) {
  for (double& r : rates) r *= 2.0;
  return SelectOrder(rates.data(), 2.0, static_cast<int>(rates.size()) - 1, rule);
}

constexpr OrderRule kPaper{OrderSelection::kPaper};
constexpr OrderRule kMargin{OrderSelection::kMargin};

TEST(OrderSelectionTest, PaperTakesTheExactMinimumTiesToTheLowerOrder) {
  EXPECT_EQ(Select({0.30, 0.2000, 0.1995, 0.25}, kPaper), 2);
  EXPECT_EQ(Select({0.30, 0.20, 0.20, 0.25}, kPaper), 1);
}

TEST(OrderSelectionTest, MarginMakesAHigherOrderWinByMoreThanTheMargin) {
  EXPECT_EQ(Select({0.30, 0.2000, 0.1995, 0.25}, kMargin), 1);  // 0.0005 < 0.001
  EXPECT_EQ(Select({0.30, 0.2000, 0.1985, 0.25}, kMargin), 2);  // 0.0015 > 0.001
  EXPECT_EQ(Select({0.30, 0.2000, 0.1985, 0.25}, OrderRule{OrderSelection::kMargin, 0.002}), 1);
  // Margin 0 is the paper's rule.
  EXPECT_EQ(Select({0.30, 0.2000, 0.1995, 0.25}, OrderRule{OrderSelection::kMargin, 0.0}), 2);
}

TEST(OrderSelectionTest, WeightedTakesTheMeanOrderOfTheNearTies) {
  const OrderRule weighted{OrderSelection::kWeighted, 0, 0.01};
  // A clear winner keeps nearly all the weight.
  EXPECT_EQ(Select({0.30, 0.30, 0.10, 0.30, 0.30, 0.30}, weighted), 2);
  // Orders 1 and 5 tied far ahead of the rest: the mean order is 3, which neither extreme gives.
  EXPECT_EQ(Select({0.40, 0.20, 0.40, 0.40, 0.40, 0.20}, weighted), 3);
  // The minimum at 5 with near-ties at 2..4: the choice shrinks towards them (mean 3.5 → 4).
  EXPECT_EQ(Select({0.40, 0.40, 0.201, 0.201, 0.201, 0.200}, weighted), 4);
  // A high temperature spreads the weight evenly: the middle order of 0..4.
  EXPECT_EQ(Select({0.40, 0.20, 0.10, 0.30, 0.25}, OrderRule{OrderSelection::kWeighted, 0, 1e6}), 2);
  // A low temperature is the exact minimum.
  EXPECT_EQ(Select({0.40, 0.20, 0.10, 0.30, 0.25}, OrderRule{OrderSelection::kWeighted, 0, 1e-6}), 2);
  EXPECT_EQ(Select({0.40, 0.099, 0.10, 0.30, 0.25}, OrderRule{OrderSelection::kWeighted, 0, 1e-6}), 1);
}

TEST(OrderSelectionTest, WeightsFollowTheTemperature) {
  const double errors[] = {0.2, 0.1, 0.1 + 0.01 * std::log(2.0)};  // weight 1
  double w[3];
  OrderWeights(errors, 1.0, 2, 0.01, w);
  EXPECT_NEAR(w[1], 2 * w[2], 1e-12);  // one temperature·ln 2 worse: half the weight
  EXPECT_NEAR(w[0] + w[1] + w[2], 1.0, 1e-12);
  EXPECT_LT(w[0], 1e-4);
  OrderWeights(errors, 0.0, 2, 0.01, w);
  EXPECT_DOUBLE_EQ(w[0], 1.0 / 3);
}

TEST(OrderSelectionTest, NoEvidenceIsOrderZeroForEveryRule) {
  const double errors[] = {0, 0, 0, 0, 0, 0};
  for (const OrderRule& rule : {kPaper, kMargin, OrderRule{}}) EXPECT_EQ(SelectOrder(errors, 0.0, 5, rule), 0);
}

TEST(OrderSelectionTest, DefaultIsTheMarginRule) {
  EXPECT_EQ(OrderRule{}.selection, OrderSelection::kMargin);
  EXPECT_EQ(OrderRule{}.temperature, kDefaultOrderTemperature);
}

}  // namespace
}  // namespace fremen::model
