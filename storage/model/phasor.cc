#include "storage/model/phasor.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fremen::model {
namespace {

// Independent multiplication chains of the harmonic table (Reset).
constexpr size_t kChains = 4;

// a·b by the textbook formula: std::complex's operator* also rescues infinities and NaNs (a call to
// __muldc3 per product), which unit phasors never are.
std::complex<double> MultiplyUnchecked(std::complex<double> a, std::complex<double> b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

}  // namespace

double ReducedPhase(double t, double period) {
  // fmod is exact for doubles, so the only rounding left is the final scaling by 2π/T.
  return 2.0 * std::numbers::pi * (std::fmod(t, period) / period);
}

PhasorTable::PhasorTable(const PeriodSet& periods, double t) { Reset(periods, t); }

void PhasorTable::Reset(const PeriodSet& periods, double t) {
  time_ = t;
  const size_t k_count = periods.size();
  cos_.resize(k_count);
  sin_.resize(k_count);
  // Zero-padded to whole vectors of kFloatLanes (see cos_f()).
  const size_t padded = (k_count + kFloatLanes - 1) / kFloatLanes * kFloatLanes;
  cos_f_.resize(padded);
  sin_f_.resize(padded);
  std::fill(cos_f_.begin() + k_count, cos_f_.end(), 0.0f);
  std::fill(sin_f_.begin() + k_count, sin_f_.end(), 0.0f);
  if (periods.harmonic()) {
    // z^(k+1) for k < K, z = e^{jω_1 t}: four interleaved chains z^(k+1) = z^(k−3)·z^4, since one
    // chain of K dependent multiplications waits on each one's latency (it measured 20 % of a
    // history's ingest); the error stays ~K·ε.
    const double phase = ReducedPhase(t, periods.period(0));
    const std::complex<double> z(std::cos(phase), std::sin(phase));
    std::complex<double> chain[kChains];
    chain[0] = z;
    for (size_t c = 1; c < kChains; ++c) chain[c] = MultiplyUnchecked(chain[c - 1], z);
    const std::complex<double> step = chain[kChains - 1];  // z^kChains
    size_t k = 0;
    for (; k + kChains <= k_count; k += kChains) {  // a fixed inner count keeps the chains in registers
      for (size_t c = 0; c < kChains; ++c) {
        cos_[k + c] = chain[c].real();
        sin_[k + c] = chain[c].imag();
        chain[c] = MultiplyUnchecked(chain[c], step);
      }
    }
    for (size_t c = 0; k < k_count; ++k, ++c) {
      cos_[k] = chain[c].real();
      sin_[k] = chain[c].imag();
    }
  } else {
    for (size_t k = 0; k < k_count; ++k) {
      const double phase = ReducedPhase(t, periods.period(k));
      cos_[k] = std::cos(phase);
      sin_[k] = std::sin(phase);
    }
  }
  for (size_t k = 0; k < k_count; ++k) {
    cos_f_[k] = static_cast<float>(cos_[k]);
    sin_f_[k] = static_cast<float>(sin_[k]);
  }
}

}  // namespace fremen::model
