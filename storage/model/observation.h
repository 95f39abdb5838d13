// One observation of one binary state: a time (seconds, any origin) and a value in [0, 1]
// (0/1 for hard observations, a probability for soft ones).
#pragma once

#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace fremen::model {

struct Observation {
  double t;
  float s;
};

// Times beyond ±1e13 s (300,000 years) are absurd for a robot and would lose sub-second precision.
inline constexpr double kMaxAbsTime = 1e13;

// Checks one observation, naming `field` (e.g. "observations[3]") in the error.
inline absl::Status ValidateObservation(const Observation& o, const std::string& field) {
  if (!std::isfinite(o.t) || std::fabs(o.t) > kMaxAbsTime) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".t must be a finite time within ±1e13 s, got ", o.t));
  }
  if (!(o.s >= 0.0f && o.s <= 1.0f)) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".s must be in [0, 1], got ", o.s));
  }
  return absl::OkStatus();
}

}  // namespace fremen::model
