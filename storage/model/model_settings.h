// The model settings of a map (docs/model.md, "Map settings"): fixed at creation, shared by all its
// states.
#pragma once

#include "storage/model/order_errors.h"
#include "storage/model/periods.h"

namespace fremen::model {

inline constexpr int kDefaultMaxOrder = 5;
inline constexpr int kMaxMaxOrder = 64;
// The defaults of new maps (docs/model.md, "Order selection"): thresholded errors decayed with a
// 7-day half-life, the margin rule. The weighted rule (squared errors, 3 days) is a map setting: it
// scores better on the shared datasets but picks orders 2-3 for states whose true order is 0 or 1
// (e2e AdminServiceTest), so it is not the default.
inline constexpr double kDefaultErrorHalfLife = 7 * 86400.0;
inline constexpr ErrorCriterion kDefaultCriterion = ErrorCriterion::kThreshold;

struct ModelSettings {
  // Ω. Default: 604800/k s, k = 1..24.
  PeriodSet periods = PeriodSet::Default();
  // L, the most components P may hold. Default: 5. REQUIRES: 0 <= max_order <= 64.
  int max_order = kDefaultMaxOrder;
  // Whether predictions may blend in the last observation (docs/model.md, "Persistence"). Default: on.
  bool persistence = true;
  // Half-life of the prequential error counters, seconds; 0 = count only since the last update.
  // Longer remembers more evidence but adapts slower to a change of the dynamics. Default: 7 days.
  double error_half_life = kDefaultErrorHalfLife;
  // How a prediction is scored against an observation. Default: thresholded error.
  ErrorCriterion criterion = kDefaultCriterion;
  // How the published order is chosen from the error rates. Default: margin 0.001.
  OrderRule order_rule;
};

}  // namespace fremen::model
