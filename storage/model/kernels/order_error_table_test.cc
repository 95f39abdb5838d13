#include "storage/model/kernels/order_error_table.h"

#include <gtest/gtest.h>

#include <random>

namespace fremen::model {
namespace {

// Random predictions and values at times that mostly advance but sometimes go back.
void ExpectSameAsOrderErrors(ErrorCriterion criterion, double half_life) {
  constexpr int kL = 5;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  OrderErrorTable table(kL, 4);
  std::vector<OrderErrors> reference(4, OrderErrors(kL));
  double t = 1.7e9;
  for (int step = 0; step < 2000; ++step) {
    t += u(rng) < 0.2 ? -3600 * u(rng) : 7200 * u(rng);
    ScanDecay decay(t, half_life);
    for (size_t i = 0; i < 4; ++i) {
      if (u(rng) < 0.3) continue;
      double predictions[kL + 1];
      for (double& p : predictions) p = 1.4 * u(rng) - 0.2;
      const float s = u(rng) < 0.5 ? 1.0f : (u(rng) < 0.5 ? 0.0f : 0.3f);
      table.Add(i, predictions, s, criterion, decay);
      reference[i].Add(t, predictions, s, criterion, half_life);
    }
  }
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(table.Get(i), reference[i]);
    for (const OrderRule& rule : {OrderRule{}, OrderRule{OrderSelection::kMargin}, OrderRule{OrderSelection::kPaper},
                                  OrderRule{OrderSelection::kWeighted, 0, 0.1}}) {
      EXPECT_EQ(table.BestOrder(i, rule), reference[i].BestOrder(rule));
    }
    for (int l = 0; l <= kL; ++l) EXPECT_EQ(table.ErrorRate(i, l), reference[i].ErrorRate(l));
  }
}

TEST(OrderErrorTableTest, AddEqualsOrderErrorsWithDecay) {
  ExpectSameAsOrderErrors(ErrorCriterion::kThreshold, 7 * 86400.0);
}
TEST(OrderErrorTableTest, AddEqualsOrderErrorsWithoutDecay) { ExpectSameAsOrderErrors(ErrorCriterion::kThreshold, 0); }
TEST(OrderErrorTableTest, AddEqualsOrderErrorsSquared) { ExpectSameAsOrderErrors(ErrorCriterion::kSquared, 86400.0); }

TEST(OrderErrorTableTest, RecordIsOneLineAtDefaultOrderAndRoundTrips) {
  EXPECT_EQ(OrderErrorTable::StrideFor(5), 64u);
  OrderErrorTable table(2, 3);
  EXPECT_EQ(table.Get(1), OrderErrors(2));
  OrderErrors errors(2);
  errors.Restore(5.0, 2.0, {1.0, 0.5, 0.25});
  table.Set(1, errors);
  EXPECT_EQ(table.Get(1), errors);
  EXPECT_EQ(table.BestOrder(1, OrderRule{}), errors.BestOrder(OrderRule{}));
  table.Reset(1);
  errors.Reset();
  EXPECT_EQ(table.Get(1), errors);
}

}  // namespace
}  // namespace fremen::model
