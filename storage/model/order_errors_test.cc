#include "storage/model/order_errors.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fremen::model {
namespace {

TEST(OrderErrorsTest, TiesGoToTheLowerOrder) {
  OrderErrors errors(3);
  const double p[] = {0.9, 0.9, 0.1, 0.1};
  errors.Add(0, p, 1.0f, ErrorCriterion::kThreshold, 0);
  EXPECT_EQ(errors.BestOrder(OrderRule{OrderSelection::kMargin}), 0);
  const double q[] = {0.1, 0.9, 0.9, 0.9};
  errors.Add(1, q, 1.0f, ErrorCriterion::kThreshold, 0);
  EXPECT_EQ(errors.BestOrder(OrderRule{OrderSelection::kMargin}), 1);
}

TEST(OrderErrorsTest, ErrorsDecayWithTheHalfLife) {
  const double week = 7 * 86400.0;
  OrderErrors errors(1);
  const double wrong_at_1[] = {0.9, 0.1};
  const double wrong_at_0[] = {0.1, 0.9};
  errors.Add(0, wrong_at_1, 1.0f, ErrorCriterion::kThreshold, week);
  errors.Add(week, wrong_at_0, 1.0f, ErrorCriterion::kThreshold, week);
  EXPECT_NEAR(errors.errors()[1], 0.5, 1e-12);  // one half-life old
  EXPECT_NEAR(errors.errors()[0], 1.0, 1e-12);
  EXPECT_NEAR(errors.weight(), 1.5, 1e-12);
  EXPECT_EQ(errors.BestOrder(OrderRule{OrderSelection::kMargin}), 1);
  // An observation older than the reference time enters already decayed: the result does not
  // depend on arrival order.
  OrderErrors reversed(1);
  reversed.Add(week, wrong_at_0, 1.0f, ErrorCriterion::kThreshold, week);
  reversed.Add(0, wrong_at_1, 1.0f, ErrorCriterion::kThreshold, week);
  EXPECT_NEAR(reversed.errors()[1], errors.errors()[1], 1e-12);
  EXPECT_NEAR(reversed.weight(), errors.weight(), 1e-12);
}

TEST(OrderErrorsTest, SquaredCriterionAndRates) {
  OrderErrors errors(1);
  const double p[] = {0.25, 1.5};  // unclamped 1.5 scores as 1
  errors.Add(0, p, 1.0f, ErrorCriterion::kSquared, 0);
  EXPECT_DOUBLE_EQ(errors.ErrorRate(0), 0.5625);
  EXPECT_DOUBLE_EQ(errors.ErrorRate(1), 0.0);
  errors.Reset();
  EXPECT_EQ(errors.weight(), 0);
  EXPECT_EQ(errors.ErrorRate(0), 0);
}

}  // namespace
}  // namespace fremen::model
