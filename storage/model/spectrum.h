// The incremental spectrum of one state (docs/model.md, "Spectrum"; the FreMEn paper's eq. 11, with
// exact mean removal).
//
// For every ω_k of Ω it keeps the running means S̄_k = (1/n)·Σ s·e^{-jω_k t} and
// Ē_k = (1/n)·Σ e^{-jω_k t}, plus the exact count n, Σs and the observed span. Then
//   γ0 = Σs / n,   γ_k = S̄_k − γ0·Ē_k   (= (S_k − γ0·E_k)/n),
// which does not depend on how the observations were split into batches or in which order they came
// (beyond rounding), and two spectra merge into the spectrum of the union of their observations.
// Running means (magnitude ≤ 1) stay accurate where raw sums would not (docs/performance.md,
// "Precision").
//
// Two precisions share the code: `Spectrum` (double) for generic states, where exactness is cheap,
// and `CompactSpectrum` (float) for the millions of grid cells, where memory bandwidth is the cost.
// Memory: a 32-byte header plus 4 reals per period (float, K = 24: 416 B; double: 800 B).
// Thread-safety: none; one writer owns a spectrum.
#pragma once

#include <complex>
#include <cstdint>
#include <span>
#include <vector>

#include "storage/model/observation.h"
#include "storage/model/periods.h"
#include "storage/model/phasor.h"

namespace fremen::model {

struct SpectrumHeader {
  double t_first = 0;  // earliest observation time (valid when n > 0)
  double t_last = 0;   // latest observation time (valid when n > 0)
  double sum_s = 0;    // Σs, exact for up to 2^53 hard observations
  uint32_t n = 0;      // number of observations
  uint32_t reserved = 0;
  bool operator==(const SpectrumHeader&) const = default;
};
static_assert(sizeof(SpectrumHeader) == 32);

// A float record is accurate to ~1e-4 up to this many observations; past it, float running means
// start losing increments below half an ulp, and the owner must widen the record to double
// (BasicSpectrum<double>::Merge of the float one is exact).
inline constexpr uint32_t kCompactRecordLimit = 1u << 20;

// Reals per period in the record body: S̄.re, S̄.im, Ē.re, Ē.im.
inline constexpr size_t kRealsPerPeriod = 4;

// The two per-period tables that fold an observation at one time into a record body:
// qs = [cos, −sin, 0, 0] and qe = [0, 0, cos, −sin] per period, so the update of a record is
// body += d·(s·qs + qe − body) with d = 1/(n+1): one vectorisable loop over 4K reals.
template <typename Real>
class ScanPhasors {
 public:
  ScanPhasors() = default;  // empty until Reset
  explicit ScanPhasors(const PhasorTable& table);
  // The phasors of another table, in the same storage (no allocation for a table of the same size).
  void Reset(const PhasorTable& table);
  double time() const { return time_; }
  size_t periods() const { return qs_.size() / kRealsPerPeriod; }
  const Real* qs() const { return qs_.data(); }
  const Real* qe() const { return qe_.data(); }

 private:
  double time_ = 0;
  std::vector<Real> qs_, qe_;
};

// Folds one observation (value s at the phasors' time) into a record. The hot path of ingest.
// Its header part: counts value s at time t; returns the body's weight d = 1/n (n counting s).
inline double FoldHeader(SpectrumHeader& h, double t, float s) {
  if (h.n == 0) {
    h.t_first = h.t_last = t;
  } else {
    if (t < h.t_first) h.t_first = t;
    if (t > h.t_last) h.t_last = t;
  }
  h.sum_s += s;
  h.n += 1;
  return 1.0 / h.n;
}

template <typename Real>
inline void FoldObservation(SpectrumHeader& h, Real* __restrict body, const ScanPhasors<Real>& ph, float s) {
  // Written as y += d·(target − y), not y = a·y + d·target: a = n/(n+1) rounds to 1 in float
  // once n passes ~1.7e7, which would silently stop the means from averaging.
  const Real d = static_cast<Real>(FoldHeader(h, ph.time(), s));
  const Real sv = s;
  const Real* __restrict qs = ph.qs();
  const Real* __restrict qe = ph.qe();
  const size_t count = ph.periods() * kRealsPerPeriod;
  for (size_t i = 0; i < count; ++i) body[i] += d * (sv * qs[i] + qe[i] - body[i]);
}

template <typename Real>
class BasicSpectrum {
 public:
  explicit BasicSpectrum(size_t periods) : body_(periods * kRealsPerPeriod, Real(0)) {}

  size_t periods() const { return body_.size() / kRealsPerPeriod; }
  const SpectrumHeader& header() const { return header_; }
  SpectrumHeader& mutable_header() { return header_; }
  Real* body() { return body_.data(); }
  const Real* body() const { return body_.data(); }

  uint32_t count() const { return header_.n; }
  // t_last − t_first; 0 with fewer than two observations.
  double span() const { return header_.n > 0 ? header_.t_last - header_.t_first : 0.0; }

  // One observation at the time of `phasors`.
  void Observe(const ScanPhasors<Real>& phasors, float s) { FoldObservation(header_, body_.data(), phasors, s); }

  // Many observations of this state at any times: summed in double, then merged in one rounding,
  // so that one batch or many batches of the same observations give the same spectrum.
  void AddBatch(std::span<const Observation> observations, const PeriodSet& periods);

  // Makes this the spectrum of the union of both states' observations.
  template <typename OtherReal>
  void Merge(const BasicSpectrum<OtherReal>& other);

  // γ0 = Σs/n (0.5 when nothing has been observed: no information either way).
  double gamma0() const { return header_.n > 0 ? header_.sum_s / header_.n : 0.5; }
  // γ_k = S̄_k − γ0·Ē_k.
  std::complex<double> gamma(size_t k) const {
    return header_.n == 0 ? std::complex<double>() : mean_s_phasor(k) - gamma0() * mean_phasor(k);
  }
  // S̄_k and Ē_k.
  std::complex<double> mean_s_phasor(size_t k) const {
    return {body_[k * kRealsPerPeriod], body_[k * kRealsPerPeriod + 1]};
  }
  std::complex<double> mean_phasor(size_t k) const {
    return {body_[k * kRealsPerPeriod + 2], body_[k * kRealsPerPeriod + 3]};
  }
  // Sets the running means of period k (for decoders and conversions).
  void set_means(size_t k, std::complex<double> s_mean, std::complex<double> e_mean);

  static constexpr size_t RecordBytes(size_t periods) {
    return sizeof(SpectrumHeader) + periods * kRealsPerPeriod * sizeof(Real);
  }

  bool operator==(const BasicSpectrum&) const = default;

 private:
  // Adds n2 observations given their raw double sums Σ s·e^{-jωt} and Σ e^{-jωt}.
  void MergeSums(uint32_t n2, double sum_s2, double t_first2, double t_last2,
                 const std::vector<std::complex<double>>& s_sums, const std::vector<std::complex<double>>& e_sums);

  SpectrumHeader header_;
  std::vector<Real> body_;
};

using Spectrum = BasicSpectrum<double>;
using CompactSpectrum = BasicSpectrum<float>;

template <typename Real>
template <typename OtherReal>
void BasicSpectrum<Real>::Merge(const BasicSpectrum<OtherReal>& other) {
  if (other.count() == 0) return;
  const double n2 = other.count();
  std::vector<std::complex<double>> s_sums(periods()), e_sums(periods());
  for (size_t k = 0; k < periods(); ++k) {
    s_sums[k] = other.mean_s_phasor(k) * n2;
    e_sums[k] = other.mean_phasor(k) * n2;
  }
  const SpectrumHeader& oh = other.header();
  MergeSums(oh.n, oh.sum_s, oh.t_first, oh.t_last, s_sums, e_sums);
}

extern template class ScanPhasors<float>;
extern template class ScanPhasors<double>;
extern template class BasicSpectrum<float>;
extern template class BasicSpectrum<double>;

}  // namespace fremen::model
