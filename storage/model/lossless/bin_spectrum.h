// The spectrum of a uniformly sampled binary signal with gaps, by FFT (docs/model.md, "Lossless history"):
//   γ0 = mean of the observed samples,  γ_k = (1/n_obs) Σ_observed (s_i − γ0) e^{−j2πki/n},  k = 0..n/2,
// for a signal of n slots. Unobserved slots contribute nothing beyond the mean: this equals the FFT of
// the signal with the gaps filled by γ0, divided by n_obs, and for a fully observed signal it is the
// plain DFT / n. Bin k is the frequency ω_k = 2πk/(nΔ) for a sampling period Δ.
//
// The transform is FFTW's real-to-complex r2c in double, in place. Plans (FFTW_ESTIMATE) are cached
// per length behind a mutex, because the FFTW planner is not thread-safe; executing a shared plan on
// new arrays is. Thread-safety: Compute may be called concurrently; a SlotSpectrum is a value.
#pragma once

#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace fremen::model {

// One slot of a reconstructed signal.
enum class SlotState : uint8_t {
  kFree = 0,
  kOccupied = 1,
  kUnobserved = 2,
};

class SlotSpectrum {
 public:
  // The spectrum of `signal` (n = signal.size() slots). REQUIRES: n < 2^31.
  static SlotSpectrum Compute(std::span<const SlotState> signal);
  // What Compute gives for n slots of which `observed` > 0 all hold `value`, without the slots: every
  // bin zero and γ0 = value (exactly 0 or 1). REQUIRES: 0 < observed ≤ n < 2^31.
  static SlotSpectrum Constant(size_t n, uint64_t observed, bool value);

  // n, the number of slots transformed.
  size_t length() const { return length_; }
  // Bins held: 0..n/2.
  size_t bins() const { return length_ / 2 + 1; }
  uint64_t observed() const { return observed_; }
  // True when every bin is zero: the signal was constant wherever it was observed, or nothing was (no
  // transform ran).
  bool all_zero() const { return all_zero_; }
  // γ0 (0 when nothing was observed).
  double gamma0() const { return gamma0_; }
  // γ_k for k in [1, n/2] (γ_0 of the mean-removed signal is 0: use gamma0()).
  std::complex<double> gamma(size_t k) const;
  // |Σ_observed (s_i − γ0) e^{−j2πki/n}|², which orders bins like |γ_k| without a division.
  // Inline: the bin scan of BinModel::FromSpectrum calls it for every bin.
  double power(size_t k) const {
    if (all_zero_) return 0.0;
    return data_[2 * k] * data_[2 * k] + data_[2 * k + 1] * data_[2 * k + 1];
  }

 private:
  SlotSpectrum() = default;
  struct FftwFree {
    void operator()(double* p) const;
  };
  size_t length_ = 0;
  uint64_t observed_ = 0;
  double gamma0_ = 0;
  bool all_zero_ = false;
  // In-place r2c layout: bin k is (data[2k], data[2k+1]). Null when all_zero_ (nothing to hold).
  std::unique_ptr<double[], FftwFree> data_;
};

}  // namespace fremen::model
