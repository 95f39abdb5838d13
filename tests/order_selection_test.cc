// End-to-end test of the order-selection setting (docs/model.md, "Order selection") against the real
// fremend: generated states (doors whose schedule changes, a weekly door, a rarely opened door,
// non-periodic and pure-noise states, a two-component signal) are fed day by day with an update
// after each day into maps with each rule; then
// - every state's selected order is the one its map's rule picks from the error rates GetStateModel
//   reports (recomputed here, independently of the daemon's code), so each setting is honoured;
// - ε_p of GetMapStats is the mean rate at those orders;
// - on the week after, the default rule's thresholded test error is within kErrBound of the paper's
//   rule and its squared error within kMseBound (the check that the new default, tuned on public
//   datasets, does not overfit them).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "client/lib/scan_builder.h"
#include "tests/client_daemon_test.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::fremen::client::ScanBuilder;
using ::fremen::client::StateSet;
using ::testing::HasSubstr;

constexpr double kDay = 86400;
constexpr double kStart = 1699920000;  // a Tuesday, midnight UTC
constexpr int kTrainDays = 21;
constexpr int kTestDays = 5;
constexpr double kStep = 900;  // one sample per 15 minutes
constexpr int kStates = 12;
// The allowed loss of the default against the paper's rule, mean over the states.
constexpr double kErrBound = 0.01;
constexpr double kMseBound = 0.005;

// The generated states: state i's probability of being 1 at time t (kinds cycle over i; the
// seeds differ) — the sample is a Bernoulli draw of it, so every state is noisy.
class World {
 public:
  explicit World(uint64_t seed) : rng_(seed) {
    for (int i = 0; i < kStates; ++i) {
      std::uniform_real_distribution<double> u(0, 1);
      shift_.push_back(2 + 4 * u(rng_));
    }
  }
  double P(int i, double t) {
    const double day = std::floor((t - kStart) / kDay);
    const double hour = std::fmod(t - kStart, kDay) / 3600;
    const int weekday = static_cast<int>(std::fmod(day + 1, 7));  // 0 = Monday
    switch (i % 6) {
      case 0: {  // an office door whose opening hours move by shift_ hours after day 10
        const double open = day < 10 ? 8 : 8 + shift_[i];
        return hour >= open && hour < open + 9 ? 0.9 : 0.1;
      }
      case 1:  // open on weekdays' working hours only
        return weekday < 5 && hour >= 9 && hour < 17 ? 0.85 : 0.05;
      case 2:  // mostly closed: open a random hour now and then (non-periodic)
        return std::fmod(std::sin(std::floor((t - kStart) / 3600) * 12.9898 + i) * 43758.5453, 1.0) > 0.97 ? 0.9
                                                                                                           : 0.02;
      case 3:  // pure noise
        return 0.3;
      case 4:  // a daily and a 12-hour component
        return std::clamp(0.5 + 0.3 * std::cos(2 * M_PI * hour / 24) + 0.15 * std::cos(2 * M_PI * hour / 12 + 1), 0.0,
                          1.0);
      default:  // a random telegraph: switches with probability 0.03 per sample (non-periodic)
        return telegraph_[i] ? 0.95 : 0.05;
    }
  }
  float Sample(int i, double t) {
    if (i % 6 == 5 && std::uniform_real_distribution<double>(0, 1)(rng_) < 0.03) telegraph_[i] = !telegraph_[i];
    return std::uniform_real_distribution<double>(0, 1)(rng_) < P(i, t) ? 1.0f : 0.0f;
  }

 private:
  std::mt19937_64 rng_;
  std::vector<double> shift_;
  bool telegraph_[kStates] = {};
};

struct Rule {
  const char* map;
  v1::ErrorCriterion criterion;  // UNSPECIFIED: the default
  std::optional<double> half_life;
  v1::OrderSelection selection;
  std::optional<double> margin, temperature;
};

// The paper's rule with the settings of maps made before the weighted one; the default; the margin
// and weighted rules at non-default values, to see the values honoured.
const Rule kRules[] = {
    {"paper", v1::ERROR_CRITERION_THRESHOLD, 7 * kDay, v1::ORDER_SELECTION_PAPER, {}, {}},
    {"default", v1::ERROR_CRITERION_UNSPECIFIED, {}, v1::ORDER_SELECTION_UNSPECIFIED, {}, {}},
    {"margin", v1::ERROR_CRITERION_SQUARED, 2 * kDay, v1::ORDER_SELECTION_MARGIN, 0.004, {}},
    {"hot", v1::ERROR_CRITERION_THRESHOLD, 4 * kDay, v1::ORDER_SELECTION_WEIGHTED, {}, 0.05},
};

// The order each rule picks from the rates r (independent of the daemon's code).
int ExpectedOrder(const v1::Map& map, const std::vector<double>& r) {
  const int n = static_cast<int>(r.size());
  if (map.order_selection() == v1::ORDER_SELECTION_WEIGHTED) {
    const double best = *std::min_element(r.begin(), r.end());
    double sum = 0, mean = 0;
    for (int l = 0; l < n; ++l) {
      const double w = std::exp(-(r[l] - best) / map.order_temperature());
      sum += w;
      mean += w * l;
    }
    return static_cast<int>(std::floor(mean / sum + 0.5));
  }
  const double margin = map.order_selection() == v1::ORDER_SELECTION_MARGIN ? map.order_margin() : 0.0;
  int pick = 0;
  for (int l = 1; l < n; ++l) {
    if (r[l] < r[pick] - margin) pick = l;
  }
  return pick;
}

class OrderSelectionTest : public ClientDaemonTest {
 protected:
  void SetUp() override {
    DaemonTest::SetUp();
    if (HasFatalFailure()) return;
    ConnectClient();
  }

  v1::Map Create(const Rule& rule) {
    v1::Map map = GenericMapSpec(rule.map);
    map.set_shards(1);
    map.set_persistence(false);
    map.set_criterion(rule.criterion);
    if (rule.half_life) map.set_error_half_life_seconds(*rule.half_life);
    map.set_order_selection(rule.selection);
    if (rule.margin) map.set_order_margin(*rule.margin);
    if (rule.temperature) map.set_order_temperature(*rule.temperature);
    auto created = client_->CreateMap(map);
    EXPECT_TRUE(created.ok()) << created.status();
    return created.ok() ? *created : v1::Map();
  }
};

TEST_F(OrderSelectionTest, EachRuleIsHonouredAndTheDefaultIsNotWorseThanThePapersOnGeneratedData) {
  std::vector<v1::Map> maps;
  for (const Rule& rule : kRules) maps.push_back(Create(rule));
  ASSERT_FALSE(HasFailure());
  // The defaults filled in, and the values given kept.
  EXPECT_EQ(maps[1].order_selection(), v1::ORDER_SELECTION_MARGIN);
  EXPECT_EQ(maps[1].order_margin(), 0.001);
  EXPECT_EQ(maps[1].criterion(), v1::ERROR_CRITERION_THRESHOLD);
  EXPECT_EQ(maps[1].error_half_life_seconds(), 7 * kDay);
  EXPECT_EQ(maps[0].order_selection(), v1::ORDER_SELECTION_PAPER);
  EXPECT_EQ(maps[2].order_margin(), 0.004);
  EXPECT_EQ(maps[3].order_temperature(), 0.05);
  for (const v1::Map& map : maps) {
    auto got = client_->GetMap(map.name());
    ASSERT_TRUE(got.ok()) << got.status();
    EXPECT_EQ(got->order_selection(), map.order_selection()) << map.name();
  }

  // Day by day: the same samples into every map, then each map's nightly update.
  World world(16);
  std::vector<std::pair<double, std::vector<float>>> test;
  for (int day = 0; day < kTrainDays + kTestDays; ++day) {
    std::vector<ScanBuilder> scans;
    for (double t = kStart + day * kDay; t < kStart + (day + 1) * kDay; t += kStep) {
      std::vector<float> s(kStates);
      for (int i = 0; i < kStates; ++i) s[i] = world.Sample(i, t);
      if (day >= kTrainDays) {
        test.emplace_back(t, s);
        continue;
      }
      ScanBuilder scan(t);
      for (int i = 0; i < kStates; ++i) scan.AddState(i + 1, s[i]);
      scans.push_back(scan);
    }
    if (day >= kTrainDays) continue;
    for (const v1::Map& map : maps) {
      auto session = client_->OpenIngest(map.name());
      ASSERT_TRUE(session.ok()) << session.status();
      for (const ScanBuilder& scan : scans) {
        auto built = ScanBuilder(scan).Build();
        ASSERT_TRUE(built.ok()) << built.status();
        ASSERT_TRUE((*session)->Send(*std::move(built)).ok());
      }
      ASSERT_TRUE((*session)->Close(absl::Seconds(60)).ok());
      UpdateAndWait(map.name());
    }
  }

  std::vector<uint64_t> ids;
  for (int i = 0; i < kStates; ++i) ids.push_back(i + 1);
  std::vector<double> times;
  for (const auto& [t, s] : test) times.push_back(t);
  std::vector<double> err(maps.size()), mse(maps.size());
  for (size_t m = 0; m < maps.size(); ++m) {
    const v1::Map& map = maps[m];
    SCOPED_TRACE(map.name());
    // The rule, state by state, and ε_p as the mean rate at the selected orders.
    double rate_sum = 0;
    int with_evidence = 0;
    std::vector<int> orders;
    for (uint64_t id : ids) {
      v1::StateRef ref;
      ref.set_id(id);
      auto model = client_->GetStateModel(map.name(), ref);
      ASSERT_TRUE(model.ok()) << model.status();
      ASSERT_TRUE(model->has_value());
      const v1::StateModel& sm = **model;
      std::vector<double> rates;
      for (const v1::OrderError& e : sm.order_errors()) rates.push_back(e.error());
      ASSERT_EQ(rates.size(), 6u);
      ASSERT_GT(sm.order_errors(0).weight(), 0);
      EXPECT_EQ(static_cast<int>(sm.selected_order()), ExpectedOrder(map, rates)) << "state " << id;
      orders.push_back(static_cast<int>(sm.selected_order()));
      rate_sum += rates[sm.selected_order()];
      ++with_evidence;
    }
    auto stats = client_->GetMapStats(map.name());
    ASSERT_TRUE(stats.ok()) << stats.status();
    EXPECT_NEAR(stats->mean_prediction_error(), rate_sum / with_evidence, 1e-6);

    auto predictions = client_->Predict(map.name(), StateSet::Ids(ids), times);
    ASSERT_TRUE(predictions.ok()) << predictions.status();
    std::vector<double> kind_err(6);  // by the World's kinds, for the printed figures
    for (size_t k = 0; k < test.size(); ++k) {
      for (int i = 0; i < kStates; ++i) {
        const double p = predictions->probability(k, i), s = test[k].second[i];
        err[m] += std::fabs((p > 0.5 ? 1.0 : 0.0) - s);
        kind_err[i % 6] += std::fabs((p > 0.5 ? 1.0 : 0.0) - s) / (test.size() * kStates / 6);
        mse[m] += (p - s) * (p - s);
      }
    }
    err[m] /= test.size() * kStates;
    mse[m] /= test.size() * kStates;
    std::string order_list;
    for (int o : orders) order_list += std::to_string(o) + " ";
    std::printf("order selection %-8s test err %.4f mse %.4f orders %s| err by kind (moved, weekly, rare, noise, "
                "two-component, telegraph) %.4f %.4f %.4f %.4f %.4f %.4f\n",
                map.name().c_str(), err[m], mse[m], order_list.c_str(), kind_err[0], kind_err[1], kind_err[2],
                kind_err[3], kind_err[4], kind_err[5]);
  }
  EXPECT_LE(err[1], err[0] + kErrBound);
  EXPECT_LE(mse[1], mse[0] + kMseBound);
}

TEST_F(OrderSelectionTest, BadSettingsAreInvalidArgumentNamingTheField) {
  v1::Map map = GenericMapSpec("bad");
  map.set_order_temperature(0);
  auto created = client_->CreateMap(map);
  EXPECT_EQ(created.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(created.status().message(), HasSubstr("map.order_temperature"));
  map = GenericMapSpec("bad");
  map.set_order_margin(-1);
  created = client_->CreateMap(map);
  EXPECT_EQ(created.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(created.status().message(), HasSubstr("map.order_margin"));
  map = GenericMapSpec("bad");
  map.set_order_selection(static_cast<v1::OrderSelection>(9));
  created = client_->CreateMap(map);
  EXPECT_EQ(created.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(created.status().message(), HasSubstr("map.order_selection"));
  // The daemon keeps serving.
  EXPECT_TRUE(client_->CreateMap(GenericMapSpec("good")).ok());
}

}  // namespace
}  // namespace fremen::testing
