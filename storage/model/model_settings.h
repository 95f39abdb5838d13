// The model settings of a map (docs/model.md, "Map settings"): fixed at creation, shared by all its
// states.
#pragma once

#include "storage/model/order_errors.h"
#include "storage/model/periods.h"

namespace fremen::model {

inline constexpr int kDefaultMaxOrder = 5;
inline constexpr int kMaxMaxOrder = 64;
inline constexpr double kDefaultErrorHalfLife = 7 * 86400.0;

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
  ErrorCriterion criterion = ErrorCriterion::kThreshold;
};

}  // namespace fremen::model
