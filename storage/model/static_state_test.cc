#include "storage/model/static_state.h"

#include <gtest/gtest.h>

#include "storage/model/test_signals.h"

namespace fremen::model {
namespace {

TEST(StaticStateTest, KeepsCountValueAndSpanInSixteenBytes) {
  StaticState state;
  EXPECT_TRUE(state.Accepts(1));
  EXPECT_FALSE(state.Accepts(0.5f));
  for (int i = 0; i < 1000; ++i) state.Observe(1.7e9 + 60.0 * i, 1);
  EXPECT_EQ(state.count(), 1000u);
  EXPECT_EQ(state.value(), 1);
  EXPECT_DOUBLE_EQ(state.t_first, 1.7e9);
  EXPECT_NEAR(state.t_last(), 1.7e9 + 59940, 1e-2);
  EXPECT_FALSE(state.Accepts(0));
  EXPECT_TRUE(state.Accepts(1));
}

TEST(StaticStateTest, PromotionOfARegularlySampledStateEqualsTheFullModel) {
  ModelSettings settings;
  StaticState compact;
  StateModel full(settings);
  for (double t : testing::UniformTimes(20000, 1.7e9, 61)) {
    compact.Observe(t, 0);
    full.Observe(t, 0);
  }
  StateModel promoted(settings);
  compact.Promote(settings, promoted);
  // The change arrives: both models must agree from here on.
  full.Observe(compact.t_last() + 61, 1);
  promoted.Observe(compact.t_last() + 61, 1);
  EXPECT_EQ(promoted.spectrum().count(), full.spectrum().count());
  EXPECT_DOUBLE_EQ(promoted.spectrum().gamma0(), full.spectrum().gamma0());
  for (size_t k = 0; k < settings.periods.size(); ++k) {
    EXPECT_LT(std::abs(promoted.spectrum().gamma(k) - full.spectrum().gamma(k)), 1e-6) << "k=" << k;
  }
  EXPECT_EQ(promoted.persistence().s_last, full.persistence().s_last);
  EXPECT_NEAR(promoted.persistence().inv_tau, full.persistence().inv_tau, 1e-9);
  EXPECT_EQ(promoted.order_errors().errors(), full.order_errors().errors());
  EXPECT_EQ(promoted.has_published(), full.has_published());
  EXPECT_NEAR(promoted.Predict(compact.t_last()), full.Predict(compact.t_last()), 1e-9);
}

}  // namespace
}  // namespace fremen::model
