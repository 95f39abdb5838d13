// A state that has never changed value (docs/model.md, "Never-changed states": they cost almost
// nothing). 16 bytes: its value, count and observed span. Its spectrum is exactly γ0 = value with
// every γ_k = 0, its persistence rate is 0 and it is implicitly published as order 0, so none of
// those need storing until the first change.
//
// The one thing the compact form cannot keep is Ē_k, the mean phasor of its past observation times.
// On the first change, Promote() rebuilds it as if the n past observations had been evenly spread
// over [t_first, t_last] — exact for regularly sampled states (and the phasor sums of a long span
// average out anyway). Thread-safety: a value type.
#pragma once

#include <algorithm>
#include <cstdint>

#include "storage/model/state_model.h"

namespace fremen::model {

struct StaticState {
  double t_first = 0;     // first observation
  float span = 0;         // t_last − t_first, s (float: 1e-7 relative is ample for the rate of a span)
  uint32_t count_value = 0;  // n << 1 | value

  uint32_t count() const { return count_value >> 1; }
  float value() const { return static_cast<float>(count_value & 1u); }
  double t_last() const { return t_first + span; }

  // Whether a value can be kept in this form: hard (0 or 1) and equal to the held value.
  bool Accepts(float s) const { return (s == 0.0f || s == 1.0f) && (count() == 0 || s == value()); }
  // REQUIRES: Accepts(s) and count() < 2^31 − 1.
  void Observe(double t, float s);

  // The equivalent full model, ready to take the observation that changes the state.
  template <typename Real>
  void Promote(const ModelSettings& settings, BasicStateModel<Real>& out) const;

  bool operator==(const StaticState&) const = default;
};
// Inline: the write path calls it for most observations of a mostly static map.
inline void StaticState::Observe(double t, float s) {
  if (count() == 0) {
    t_first = t;
    span = 0;
  } else {
    const double last = std::max(t_last(), t);
    t_first = std::min(t_first, t);
    span = static_cast<float>(last - t_first);
  }
  count_value = ((count() + 1) << 1) | (s == 1.0f ? 1u : 0u);
}

static_assert(sizeof(StaticState) == 16);

extern template void StaticState::Promote(const ModelSettings&, BasicStateModel<float>&) const;
extern template void StaticState::Promote(const ModelSettings&, BasicStateModel<double>&) const;

}  // namespace fremen::model
