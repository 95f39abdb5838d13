// The set Ω of modelled periods of a map (docs/model.md, "Map settings" and "Spectrum").
//
// A PeriodSet is an immutable list of periods in seconds, longest first. The model of every state of
// a map is expressed against the same Ω, so a batch of observations taken at one time can share one
// phasor table. Thread-safe: immutable after construction.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace fremen::model {

inline constexpr double kWeekSeconds = 604800.0;
inline constexpr int kDefaultPeriodCount = 24;

class PeriodSet {
 public:
  // T_k = longest / k for k = 1..count. With floor_periods, T_k = floor(longest / k), the choice of
  // the original FremenServer (needed to reproduce its figures exactly).
  // REQUIRES: longest > 0 and finite, 1 <= count <= 65535 (a period index fits in 16 bits).
  static absl::StatusOr<PeriodSet> Harmonics(double longest, int count, bool floor_periods = false);

  // The default Ω: the 24 periods of a week down to 7 h (604800 / k s, k = 1..24).
  static PeriodSet Default();

  // An explicit list (seconds, each > 0 and finite, at most 65535 of them).
  static absl::StatusOr<PeriodSet> FromPeriods(std::vector<double> periods);

  size_t size() const { return periods_.size(); }
  double period(size_t k) const { return periods_[k]; }
  const std::vector<double>& periods() const { return periods_; }

  // Whether T_k = T_1 / k exactly for every k (the default Ω, and Harmonics without floor_periods):
  // then every phasor is a power of the first one (PhasorTable).
  bool harmonic() const { return harmonic_; }

 private:
  explicit PeriodSet(std::vector<double> periods);
  std::vector<double> periods_;
  bool harmonic_;
};

}  // namespace fremen::model
