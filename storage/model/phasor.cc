#include "storage/model/phasor.h"

#include <cmath>
#include <numbers>

namespace fremen::model {

double ReducedPhase(double t, double period) {
  // fmod is exact for doubles, so the only rounding left is the final scaling by 2π/T.
  return 2.0 * std::numbers::pi * (std::fmod(t, period) / period);
}

PhasorTable::PhasorTable(const PeriodSet& periods, double t) : time_(t) {
  const size_t k_count = periods.size();
  cos_.resize(k_count);
  sin_.resize(k_count);
  cos_f_.resize(k_count);
  sin_f_.resize(k_count);
  for (size_t k = 0; k < k_count; ++k) {
    const double phase = ReducedPhase(t, periods.period(k));
    cos_[k] = std::cos(phase);
    sin_[k] = std::sin(phase);
    cos_f_[k] = static_cast<float>(cos_[k]);
    sin_f_[k] = static_cast<float>(sin_[k]);
  }
}

}  // namespace fremen::model
