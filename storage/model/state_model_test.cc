#include "storage/model/state_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "storage/model/test_signals.h"

namespace fremen::model {
namespace {

using testing::RandomTimes;
using testing::Sample;
using testing::SampleBernoulli;
using testing::UniformTimes;

// Three weeks of minute samples; a week is learned, published, then two weeks are scored
// prequentially before the update chooses the order.
template <typename Real>
int SelectedOrder(const std::vector<Observation>& obs, const OrderRule& rule = OrderRule{}) {
  ModelSettings settings;
  settings.order_rule = rule;
  BasicStateModel<Real> model(settings);
  const size_t split = obs.size() / 3;
  model.AddBatch(std::span(obs).first(split));
  model.Publish(settings.max_order);
  model.AddBatch(std::span(obs).subspan(split));
  return model.Update();
}

TEST(StateModelTest, OrderSelectionPicksTwoOnATwoComponentNoisySignal) {
  std::mt19937_64 rng(21);
  std::normal_distribution<double> noise(0, 0.1);
  const auto obs = Sample(UniformTimes(3 * 10080, 0, 60), [&](double t) {
    const double p = 0.5 + 0.25 * std::cos(ReducedPhase(t, 86400)) + 0.2 * std::cos(ReducedPhase(t, 43200) + 2.0);
    return static_cast<float>(std::clamp(p + noise(rng), 0.0, 1.0));
  });
  // The margin rule (the default) on the default thresholded errors; the paper's exact minimum
  // takes noise components there (order 4), so it is not asserted.
  EXPECT_EQ(SelectedOrder<double>(obs, OrderRule{OrderSelection::kMargin}), 2);
  EXPECT_EQ(SelectedOrder<float>(obs, OrderRule{OrderSelection::kMargin}), 2);
  // Orders 2..5 tie (the extra components are noise), so the weighted rule's mean order lies among
  // them: never below the two real components.
  EXPECT_GE(SelectedOrder<double>(obs, OrderRule{OrderSelection::kWeighted}), 2);
  EXPECT_LE(SelectedOrder<double>(obs, OrderRule{OrderSelection::kWeighted}), 4);
}

TEST(StateModelTest, OrderSelectionPicksZeroOnNoise) {
  const auto obs = SampleBernoulli(UniformTimes(3 * 10080, 0, 60), [](double) { return 0.3; }, 99);
  EXPECT_EQ(SelectedOrder<double>(obs, OrderRule{OrderSelection::kMargin}), 0);
  EXPECT_EQ(SelectedOrder<float>(obs, OrderRule{OrderSelection::kMargin}), 0);
}

// On noise every order's rate ties, so the weighted rule's mean order lands in the middle (a known
// cost of the rule, docs/model.md): the components it then uses are noise, but small ones, so its
// predictions stay near the mean and its squared error near order 0's.
TEST(StateModelTest, WeightedRuleOnNoiseStaysNearTheMean) {
  const auto obs = SampleBernoulli(UniformTimes(3 * 10080, 0, 60), [](double) { return 0.3; }, 99);
  ModelSettings settings;
  StateModel model(settings);
  const size_t split = obs.size() / 3;
  model.AddBatch(std::span(obs).first(split));
  model.Publish(settings.max_order);
  model.AddBatch(std::span(obs).subspan(split));
  model.Update();
  const OrderErrors& errors = model.order_errors();
  EXPECT_LT(errors.ErrorRate(model.published().order()), errors.ErrorRate(0) + 0.001);
  for (const Component& c : model.published().components()) EXPECT_LT(c.amplitude(), 0.05);
}

template <typename Real>
void CheckTimeOriginDoesNotMatter() {
  ModelSettings settings;
  BasicStateModel<Real> near_zero(settings), at_epoch(settings);
  // The shift is a whole number of weeks so that the same instants of the week are compared.
  const double shift = std::round(1.7e9 / 604800) * 604800;
  const auto obs = SampleBernoulli(RandomTimes(30000, 0, 3 * 604800.0, 8),
                                   [](double t) { return 0.5 + 0.45 * std::cos(ReducedPhase(t, 86400)); }, 3);
  std::vector<Observation> shifted = obs;
  for (Observation& o : shifted) o.t += shift;
  near_zero.AddBatch(obs);
  at_epoch.AddBatch(shifted);
  near_zero.Publish(5);
  at_epoch.Publish(5);
  double worst = 0;
  for (double t = 3 * 604800.0; t < 4 * 604800.0; t += 977) {
    for (bool persistence : {false, true}) {
      worst = std::max(worst, std::fabs(near_zero.Predict(t, persistence) - at_epoch.Predict(t + shift, persistence)));
    }
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(StateModelTest, MovingTheTimeOriginChangesNoPredictionDouble) { CheckTimeOriginDoesNotMatter<double>(); }
TEST(StateModelTest, MovingTheTimeOriginChangesNoPredictionFloat) { CheckTimeOriginDoesNotMatter<float>(); }

TEST(StateModelTest, WholeModelIsInvariantToBatchingAndOrder) {
  ModelSettings settings;
  const auto obs = SampleBernoulli(UniformTimes(2 * 10080, 1.6e9, 60), [](double t) {
    return 0.5 + 0.3 * std::cos(ReducedPhase(t, 86400)) + 0.2 * std::cos(ReducedPhase(t, 43200) + 2.0);
  }, 4);
  StateModel one(settings), split(settings), shuffled(settings), single(settings);
  const auto first = std::span(obs).first(obs.size() / 2);
  for (StateModel* m : {&one, &split, &shuffled, &single}) {
    m->AddBatch(first);
    m->Publish(3);
  }
  const auto rest = std::span(obs).subspan(obs.size() / 2);
  one.AddBatch(rest);
  for (size_t i = 0; i < rest.size(); i += 97) split.AddBatch(rest.subspan(i, std::min<size_t>(97, rest.size() - i)));
  for (const Observation& o : rest) single.Observe(o.t, o.s);
  std::vector<Observation> mixed(rest.begin(), rest.end());
  std::shuffle(mixed.begin(), mixed.end(), std::mt19937_64(1));
  shuffled.AddBatch(mixed);

  for (StateModel* m : {&split, &shuffled, &single}) {
    for (int l = 0; l <= 5; ++l) EXPECT_NEAR(m->order_errors().errors()[l], one.order_errors().errors()[l], 1e-6);
    EXPECT_NEAR(m->order_errors().weight(), one.order_errors().weight(), 1e-6);
    EXPECT_EQ(m->persistence().t_last, one.persistence().t_last);
    EXPECT_NEAR(m->persistence().inv_tau, one.persistence().inv_tau, 1e-9);
    for (size_t k = 0; k < settings.periods.size(); ++k) {
      EXPECT_LT(std::abs(m->spectrum().gamma(k) - one.spectrum().gamma(k)), 1e-5);
    }
    EXPECT_EQ(m->Update(), one.Update());
  }
}

TEST(StateModelTest, UnpublishedStatePredictsItsMeanAndIsNotScored) {
  ModelSettings settings;
  StateModel model(settings);
  EXPECT_DOUBLE_EQ(model.Predict(0.0), 0.5);
  model.Observe(0, 1);
  model.Observe(60, 1);
  model.Observe(120, 0);
  EXPECT_NEAR(model.Predict(1000.0), 2.0 / 3, 1e-12);
  EXPECT_EQ(model.order_errors().weight(), 0);
  EXPECT_FALSE(model.has_published());
}

TEST(StateModelTest, PersistenceIsUsedOnlyWhenAskedAndEnabled) {
  ModelSettings settings;
  StateModel model(settings);
  for (int i = 0; i < 100; ++i) model.Observe(i * 600.0, (i / 6) % 2 ? 1.0f : 0.0f);
  model.Publish(0);
  const double t = model.persistence().t_last + 1;
  EXPECT_NEAR(model.Predict(t, true), model.persistence().s_last, 0.01);
  EXPECT_NEAR(model.Predict(t, false), model.spectrum().gamma0(), 1e-6);
  ModelSettings off;
  off.persistence = false;
  StateModel no_persistence(off);
  no_persistence.Observe(0, 1);
  no_persistence.Observe(10, 0);
  no_persistence.Publish(0);
  EXPECT_NEAR(no_persistence.Predict(11.0, true), 0.5, 1e-6);
}

}  // namespace
}  // namespace fremen::model
