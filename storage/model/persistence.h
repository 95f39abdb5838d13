// The persistence model of one state (docs/model.md, "Persistence"; the FreMEn paper's eq. 12-13).
//
// Keeps the last observation (t_l, s(t_l)) and τ⁻¹, the running mean of |s(t) − s(t_l)|/(t − t_l)
// over consecutive observations; the short-term prediction blends the last observation into the
// periodic model p(t): p'(t) = s(t_l)·e^{−|t−t_l|/τ} + p(t)·(1 − e^{−|t−t_l|/τ}). (The paper prints the
// exponent without its minus sign; it must decay.) Observations older than t_l do not move it: the
// rate is defined over time-ordered neighbours. 24 bytes. Thread-safety: none (a value type).
#pragma once

#include <cstdint>

namespace fremen::model {

struct Persistence {
  double t_last = 0;      // t_l (valid when observed)
  float s_last = 0;       // s(t_l)
  float inv_tau = 0;      // τ⁻¹ in 1/s, running mean
  uint32_t samples = 0;   // number of rate samples in inv_tau
  uint32_t observed = 0;  // 1 once anything was observed

  void Observe(double t, float s);
  // p'(t) given the periodic model's p(t). Before any observation, p(t) itself.
  double Predict(double t, double p) const;

  bool operator==(const Persistence&) const = default;
};
static_assert(sizeof(Persistence) == 24);

}  // namespace fremen::model
