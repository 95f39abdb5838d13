// Phasors e^{-jωt} of every period of Ω at one time, computed once and shared by every state
// observed or predicted at that time (docs/performance.md, "One scan shares its phasors").
//
// Phases are range-reduced in double precision: ω·t at t ≈ 1.7e9 s is garbage in float (128 s ulp),
// and even in double loses digits unless t is first reduced modulo the period (fmod is exact).
// For a harmonic Ω (T_k = T_1 / k, the default) the table is e^{-jω_1 t} raised to the powers
// 1..K by complex multiplication in double: one fmod and one sincos a table instead of K of each,
// which is what a history (a time per observation) pays per observation. It differs from the phases
// reduced one by one mostly by the rounding of T_1/k to a double (3e-11 for K = 24 at t = 4e9; the
// table is the exact harmonic), far below a float's 6e-8 (phasor_test.cc).
// Thread-safety: a PhasorTable is a value; build one per time and share it read-only.
#pragma once

#include <complex>
#include <vector>

#include "storage/model/periods.h"

namespace fremen::model {

// The phase ω·t of period T at time t, reduced to (-2π, 2π) without losing precision.
double ReducedPhase(double t, double period);

class PhasorTable {
 public:
  PhasorTable(const PeriodSet& periods, double t);

  // The table of the same Ω at another time, in the same storage (no allocation when Ω is the same).
  void Reset(const PeriodSet& periods, double t);

  double time() const { return time_; }
  size_t size() const { return cos_.size(); }

  // cos(ω_k t) and sin(ω_k t), in double, for exact single-state work.
  double cos(size_t k) const { return cos_[k]; }
  double sin(size_t k) const { return sin_[k]; }
  // e^{-jω_k t}.
  std::complex<double> conj_phasor(size_t k) const { return {cos_[k], -sin_[k]}; }

  // The same values as floats, for the vectorised kernels; zeros follow up to a multiple of
  // kFloatLanes entries, so that a kernel may hold the table as whole vectors of sixteen (AVX-512) or
  // eight (PredictColumns looks periods up with vector permutes).
  static constexpr size_t kFloatLanes = 16;
  const float* cos_f() const { return cos_f_.data(); }
  const float* sin_f() const { return sin_f_.data(); }

 private:
  double time_;
  std::vector<double> cos_, sin_;
  std::vector<float> cos_f_, sin_f_;
};

}  // namespace fremen::model
