// The published model P of one state (docs/model.md, "Published model P"; the FreMEn paper's
// eq. 9-10) and what is computed from it.
//
// P holds α0 = γ0 and the L strongest eligible components of the spectrum, sorted by amplitude, and
// the selected order l ≤ L:  p(t) = ς(α0 + Σ_{j<l} α_j cos(ω_j t + φ_j)),  α_j = 2|γ_j|, φ_j = arg γ_j,
// ς = clamp to [0, 1]. A component is kept as (period index k, a = α cos φ, b = α sin φ), so that
// α cos(ωt + φ) = a·cos ωt − b·sin ωt needs no trigonometry per state once the phasors of t are known.
// P is refreshed by the update job, not on every observation; queries read it.
// Thread-safety: a value type.
#pragma once

#include <complex>
#include <cstdint>
#include <vector>

#include "storage/model/periods.h"
#include "storage/model/phasor.h"
#include "storage/model/spectrum.h"

namespace fremen::model {

struct Component {
  uint16_t k = 0;  // index of ω in Ω
  float a = 0;     // α·cos φ
  float b = 0;     // α·sin φ
  double amplitude() const;
  double phase() const;
  bool operator==(const Component&) const = default;
};

// Periods longer than this share of the observed span cannot be estimated yet (the original code's
// gate 1.5·T ≤ span).
inline constexpr double kSpanGate = 2.0 / 3.0;

class PublishedModel {
 public:
  PublishedModel() = default;
  // A model with only a mean: what a state predicts before its first publication.
  static PublishedModel MeanOnly(double alpha0);
  // A model from its stored parts (decoders). REQUIRES: components sorted by amplitude.
  static PublishedModel Restore(float alpha0, int order, std::vector<Component> components);

  // The top-`max_order` eligible components of `spectrum` by amplitude, with selected order
  // `order` (REQUIRES: 0 <= order <= max_order).
  template <typename Real>
  static PublishedModel FromSpectrum(const BasicSpectrum<Real>& spectrum, const PeriodSet& periods, int max_order,
                                     int order);

  float alpha0() const { return alpha0_; }
  int order() const { return order_; }
  // Components held (≤ L; fewer when fewer periods were eligible).
  const std::vector<Component>& components() const { return components_; }
  void set_order(int order) { order_ = static_cast<uint8_t>(order); }

  // p(t) at `order` (-1: the selected order; an order above the components held uses all of them),
  // clamped to [0, 1]. `phasors` must be of the map's Ω.
  double Predict(const PhasorTable& phasors, int order = -1) const;
  // The unclamped value, for the prequential scoring of every order in one pass: out[l] for l = 0..L.
  void PredictAllOrders(const PhasorTable& phasors, int max_order, double* out) const;

  bool operator==(const PublishedModel&) const = default;

 private:
  // The L strongest eligible (k, γ_k) pairs, given all γ; shared by both spectrum precisions.
  static PublishedModel FromGammas(double gamma0, const std::vector<std::complex<double>>& gammas,
                                   const PeriodSet& periods, double span, int max_order, int order);

  float alpha0_ = 0.5f;
  uint8_t order_ = 0;
  std::vector<Component> components_;
};

template <typename Real>
PublishedModel PublishedModel::FromSpectrum(const BasicSpectrum<Real>& spectrum, const PeriodSet& periods,
                                            int max_order, int order) {
  std::vector<std::complex<double>> gammas(spectrum.count() > 0 ? spectrum.periods() : 0);
  for (size_t k = 0; k < gammas.size(); ++k) gammas[k] = spectrum.gamma(k);
  return FromGammas(spectrum.gamma0(), gammas, periods, spectrum.span(), max_order, order);
}

inline double Clamp01(double p) { return p < 0 ? 0 : (p > 1 ? 1 : p); }

// s'(t, c) = p(t) ≥ c (eq. 9).
inline bool EstimateState(double p, double confidence) { return p >= confidence; }

// Anomalous at confidence c: s = 1 while p < 1 − c, or s = 0 while p > c (docs/model.md,
// "Queries"). Soft observations count as 1 when ≥ 0.5.
inline bool IsAnomalous(double s, double p, double confidence) {
  return s >= 0.5 ? p < 1.0 - confidence : p > confidence;
}

// Binary entropy of p in bits.
double Entropy(double p);

}  // namespace fremen::model
