#include "storage/model/periods.h"

#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace fremen::model {

namespace {
constexpr size_t kMaxPeriods = 65535;
}

PeriodSet::PeriodSet(std::vector<double> periods) : periods_(std::move(periods)), harmonic_(true) {
  for (size_t k = 1; k < periods_.size() && harmonic_; ++k) {
    harmonic_ = periods_[k] == periods_[0] / static_cast<double>(k + 1);
  }
}

absl::StatusOr<PeriodSet> PeriodSet::Harmonics(double longest, int count, bool floor_periods) {
  if (!std::isfinite(longest) || longest <= 0) {
    return absl::InvalidArgumentError(absl::StrCat("longest period must be a positive number of seconds, got ", longest));
  }
  if (count < 1 || static_cast<size_t>(count) > kMaxPeriods) {
    return absl::InvalidArgumentError(absl::StrCat("period count must be in [1, 65535], got ", count));
  }
  std::vector<double> periods;
  periods.reserve(count);
  for (int k = 1; k <= count; ++k) {
    double period = longest / k;
    if (floor_periods) period = std::floor(period);
    if (period <= 0) {
      return absl::InvalidArgumentError(absl::StrCat("period ", k, " of ", count, " rounds down to zero"));
    }
    periods.push_back(period);
  }
  return PeriodSet(std::move(periods));
}

PeriodSet PeriodSet::Default() { return *Harmonics(kWeekSeconds, kDefaultPeriodCount); }

absl::StatusOr<PeriodSet> PeriodSet::FromPeriods(std::vector<double> periods) {
  if (periods.empty() || periods.size() > kMaxPeriods) {
    return absl::InvalidArgumentError(absl::StrCat("periods must hold 1 to 65535 values, got ", periods.size()));
  }
  for (size_t i = 0; i < periods.size(); ++i) {
    if (!std::isfinite(periods[i]) || periods[i] <= 0) {
      return absl::InvalidArgumentError(absl::StrCat("periods[", i, "] must be a positive number of seconds, got ", periods[i]));
    }
  }
  return PeriodSet(std::move(periods));
}

}  // namespace fremen::model
