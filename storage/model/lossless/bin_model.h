// The published model P of a lossless history (docs/model.md, "Lossless history"): α0 and up to L
// components at FFT-bin frequencies of the slot signal it was computed from, and the selected order
// l ≤ L.
//
// With n the number of slots transformed, component j is bin k_j (period n/k_j slots) held as
// a_j = α_j cos φ_j, b_j = α_j sin φ_j (α_j = 2|γ_k|: one-sided amplitude, φ_j = arg γ_k; the Nyquist
// bin k = n/2 is its own mirror and keeps |γ_k|), with phase referenced to slot 0 (the origin t0):
//   p(slot i) = ς(α0 + Σ_{j<l} a_j cos(2π k_j i / n) − b_j sin(2π k_j i / n)),  ς = clamp to [0, 1].
// Values are stored as float: what the record holds is exactly what reconstruction computes with.
//
// The value at a slot is bit-reproducible (bin_phasor.h): the angle 2π(k·i mod n)/n is reduced in
// integers and accumulated with explicit fma in a fixed order, so BinModel::SlotValue and
// SlotPredictor agree to the bit, before and after an encode/decode round trip. This is what makes
// the threshold p ≥ 0.5 of eq. 7 safe to use for exact reconstruction.
// Thread-safety: value types; const methods may be called concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "storage/model/lossless/bin_phasor.h"
#include "storage/model/lossless/bin_spectrum.h"
#include "storage/model/varint.h"

namespace fremen::model {

// Longest signal a model may be computed from (FFTW takes an int length; k·i mod n stays in 64 bits).
inline constexpr uint64_t kMaxBinLength = (uint64_t{1} << 31) - 1;

struct BinComponent {
  uint32_t k = 0;  // bin: ω = 2πk/(nΔ)
  float a = 0;     // α·cos φ
  float b = 0;     // α·sin φ
  double amplitude() const;
  double phase() const;
  bool operator==(const BinComponent&) const = default;
};

class BinModel {
 public:
  // No model yet: p = 0 everywhere, so every occupied slot is an outlier and O is a plain run-length
  // coding of the occupied runs until the first update.
  BinModel() = default;

  // The `max_order` strongest bins of `spectrum` by |γ_k| (ties to the lower bin), sorted by
  // amplitude, with the order set to the number held. Bin 0 is α0, not a component; a bin whose
  // period n/k exceeds 2/3 of `span` (slots between the first and last observation) cannot be
  // estimated yet and is not eligible (the 2/3-span gate of docs/model.md, "Published model P").
  // REQUIRES: spectrum.length() ≤ kMaxBinLength.
  static BinModel FromSpectrum(const SlotSpectrum& spectrum, uint64_t span, int max_order);

  // n, the number of slots the model was computed from; 0 before the first update.
  uint64_t length() const { return length_; }
  float alpha0() const { return alpha0_; }
  int order() const { return order_; }
  const std::vector<BinComponent>& components() const { return components_; }
  // REQUIRES: 0 ≤ order ≤ components().size().
  void set_order(int order) { order_ = static_cast<uint8_t>(order); }

  // Unclamped p at `slot` using the first `order` components (-1: the selected order).
  // REQUIRES: order ≤ components().size().
  double SlotValue(uint64_t slot, int order = -1) const;
  // Whether SlotValue(·, order) is α0 at every slot: the components used all have zero amplitude
  // (their fma terms add ±0), as a constant signal's do. -1: the selected order.
  // REQUIRES: order ≤ components().size().
  bool IsConstant(int order = -1) const;
  // s'(slot) = p(slot) ≥ 0.5 (eq. 9 at c = 0.5) at the selected order.
  bool SlotEstimate(uint64_t slot) const { return SlotValue(slot) >= 0.5; }
  // p at a fractional slot position x = (t − t0)/Δ ≥ 0, clamped, in ordinary floating point: for
  // predictions at arbitrary times. At whole slots it is within rounding of SlotValue, not bitwise.
  double Predict(double x, int order = -1) const;

  size_t encoded_size() const;
  void EncodeTo(std::string* out) const;
  // Reads what EncodeTo wrote; errors are sticky in `reader` and name `field`.
  static BinModel Decode(ByteReader& reader, std::string_view field);

  bool operator==(const BinModel&) const = default;

 private:
  uint64_t length_ = 0;
  float alpha0_ = 0;
  uint8_t order_ = 0;
  std::vector<BinComponent> components_;
};

// Evaluates a BinModel over runs of slots without trigonometry per slot: the phasor of angle
// 2πr/n is the product (Rotate) of a coarse entry 2π(r − r mod 2^b)/n and a fine entry 2π(r mod 2^b)/n
// from two tables of about √n entries each, built once. BinModel::SlotValue computes the same two
// entries directly, so both agree to the bit. Cost: ~10 flops per component per slot.
// Thread-safety: immutable after construction; keeps a reference to the model.
class SlotPredictor {
 public:
  explicit SlotPredictor(const BinModel& model);

  // out[i] = unclamped p(begin + i) at `order` (≤ components held), i < out.size().
  void Values(uint64_t begin, int order, std::span<double> out) const;

  // Scores the model at orders 0..errors.size()−1 against `truth` (truth[i] is slot begin + i):
  // errors[l] += the number of observed slots where (p at order l ≥ 0.5) differs from the truth.
  // Orders above the components held score as all of them.
  void CountErrors(uint64_t begin, std::span<const SlotState> truth, std::span<uint64_t> errors) const;

 private:
  // out[i] += component j at slot begin + i.
  void AddComponent(size_t j, uint64_t begin, std::span<double> out) const;

  const BinModel& model_;
  int fine_bits_ = 0;
  std::vector<UnitPhasor> coarse_;
  std::vector<UnitPhasor> fine_;
};

}  // namespace fremen::model
