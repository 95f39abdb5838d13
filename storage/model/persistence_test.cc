#include "storage/model/persistence.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fremen::model {
namespace {

TEST(PersistenceTest, TendsToTheLastObservationJustAfterAndToTheModelLongAfter) {
  Persistence persistence;
  // A state that changes about once an hour.
  for (int i = 0; i < 48; ++i) persistence.Observe(i * 1800.0, (i / 2) % 2 ? 1.0f : 0.0f);
  ASSERT_GT(persistence.inv_tau, 0);
  const double t_l = persistence.t_last;
  const double s_l = persistence.s_last;
  const double p = 0.2;
  EXPECT_NEAR(persistence.Predict(t_l + 1, p), s_l, 0.01);
  EXPECT_NEAR(persistence.Predict(t_l + 30 * 86400.0, p), p, 1e-6);
  // Monotone in between.
  EXPECT_GT(std::fabs(persistence.Predict(t_l + 600, p) - p), std::fabs(persistence.Predict(t_l + 6000, p) - p));
}

TEST(PersistenceTest, RateIsTheMeanOfChangesPerSecond) {
  Persistence persistence;
  persistence.Observe(0, 0);
  persistence.Observe(10, 1);   // 0.1 /s
  persistence.Observe(20, 1);   // 0
  persistence.Observe(120, 0);  // 0.01 /s
  EXPECT_NEAR(persistence.inv_tau, (0.1 + 0 + 0.01) / 3, 1e-7);
  EXPECT_EQ(persistence.samples, 3u);
}

TEST(PersistenceTest, OlderObservationsDoNotMoveIt) {
  Persistence persistence;
  persistence.Observe(100, 1);
  persistence.Observe(50, 0);
  EXPECT_EQ(persistence.t_last, 100);
  EXPECT_EQ(persistence.s_last, 1);
  EXPECT_EQ(persistence.samples, 0u);
}

TEST(PersistenceTest, UnobservedStatePredictsTheModel) {
  EXPECT_DOUBLE_EQ(Persistence().Predict(123, 0.37), 0.37);
}

}  // namespace
}  // namespace fremen::model
