// The lossless history of one binary state (docs/model.md, "Lossless history"; the FreMEn paper's
// eq. 7-9 and 14-16).
//
// The state is sampled on a uniform grid: slot i covers [t0 + iΔ, t0 + (i+1)Δ). The history keeps
//  - P, a BinModel: α0 and up to L components at FFT-bin frequencies 2πk/(nΔ) of the reconstructed
//    signal, phase referenced to t0, with a selected order l;
//  - O, the outlier set: the slots where s'(i) = (p(i) ≥ 0.5) differs from the observation, stored
//    as toggle points (eq. 8's Δ-encoding: a point only where s' starts or stops matching);
//  - the coverage: which slots were observed, also as toggle points;
// so that s(i) = s'(i) ⊕ (i ∈ O) (eq. 7) reproduces every observed slot exactly, and an unobserved
// slot is reported as unobserved. A slot observed again keeps its latest value. Soft values are
// thresholded (s ≥ 0.5 → 1): the history is binary.
//
// Update() is the paper's model update (docs/update-job.md): reconstruct, pick the order that best
// predicted the slots observed since the last update, re-transform (FFT), publish P, rebuild O.
// ε_e and ε_p come from O and the coverage by eq. 15, in O(toggle points).
//
// No I/O and no threads; the FFT is FFTW (see bin_spectrum.h for its plan cache).
// Thread-safety: a value type; const methods may be called concurrently, mutations need one owner.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "storage/model/lossless/bin_model.h"
#include "storage/model/lossless/bin_spectrum.h"
#include "storage/model/lossless/slot_set.h"

namespace fremen::model {

class LosslessHistory {
 public:
  // First byte of an encoded record.
  static constexpr uint8_t kFormatVersion = 1;
  // Most slots a history may span: 2^30, 34 years of 1 s slots. Every update transforms all of them
  // (8 bytes a slot), so a store should also refuse times absurdly far ahead of its clock.
  static constexpr uint64_t kMaxSlots = uint64_t{1} << 30;

  // An empty history sampled every `delta` seconds from `t0`. InvalidArgument unless t0 is finite
  // within ±kMaxAbsTime and delta is finite and > 0.
  static absl::StatusOr<LosslessHistory> Create(double t0, double delta);

  double t0() const { return t0_; }
  double delta() const { return delta_; }
  // m: slots from t0 up to and including the latest observed one.
  uint64_t slot_count() const { return coverage_.empty() ? 0 : coverage_.last_point(); }
  uint64_t observed_count() const { return coverage_.Count(0, slot_count()); }
  // The first slot P had not seen when it was published (0 before the first update): ε_p's τ'.
  uint64_t update_slot() const { return update_slot_; }
  const BinModel& model() const { return model_; }
  const SlotSet& outliers() const { return outliers_; }
  const SlotSet& coverage() const { return coverage_; }

  // floor((t − t0)/Δ). InvalidArgument for a time that is not finite within ±kMaxAbsTime or is
  // before t0; OutOfRange at or beyond kMaxSlots.
  absl::StatusOr<uint64_t> SlotOf(double t) const;
  // The start of slot i, where p is evaluated for it.
  double SlotTime(uint64_t slot) const { return t0_ + static_cast<double>(slot) * delta_; }

  // Adds the measurement s (in [0, 1]) at time t by eq. 8: if s(t) by eq. 7 differs, t's slot is
  // toggled in O. Errors as SlotOf, and InvalidArgument for s outside [0, 1].
  absl::Status Add(double t, float s);
  // The same for a slot index. OutOfRange at or beyond kMaxSlots.
  absl::Status AddSlot(uint64_t slot, bool s);

  // The exact observed states of slots [begin, end); unobserved slots (and those after the latest
  // observation) as kUnobserved. InvalidArgument when begin > end or end > kMaxSlots.
  absl::StatusOr<std::vector<SlotState>> Reconstruct(uint64_t begin, uint64_t end) const;
  // The same into out[i] for slot begin + i. REQUIRES: begin + out.size() ≤ kMaxSlots.
  void ReconstructInto(uint64_t begin, std::span<SlotState> out) const;

  // p(t) from P (clamped, ordinary floating point; for predictions, not for reconstruction).
  double Predict(double t, int order = -1) const;

  // The model update. Picks the order l in 0..max_order with the fewest wrong estimates s' on the
  // slots observed since the last update, scored with the P published then, which predicted them (the
  // prequential choice of docs/model.md, "Order selection"; ties to the lower order). When that P has
  // no components (the first update, or none were eligible yet) the new components are scored on all
  // data instead; with nothing observed since, the order stays. A given `order` skips the choice.
  // Then publishes the max_order strongest eligible bins of the FFT of the reconstruction, rebuilds O
  // against them and sets update_slot() to m. Returns the order published (at most the components
  // found). InvalidArgument for max_order outside [0, kMaxMaxOrder] or order outside [0, max_order].
  // With nothing observed, changes nothing.
  absl::StatusOr<int> Update(int max_order, std::optional<int> order = std::nullopt);

  // Eq. 15 restricted to observed slots: wrong = |O ∩ observed ∩ [begin, end)|, the slots where
  // s' ≠ s; observed = |observed ∩ [begin, end)|.
  struct Error {
    uint64_t wrong = 0;
    uint64_t observed = 0;
    double rate() const { return observed > 0 ? static_cast<double>(wrong) / static_cast<double>(observed) : 0.0; }
  };
  Error ErrorBetween(uint64_t begin, uint64_t end) const;
  // ε_e: over all observed slots.
  Error EstimationError() const { return ErrorBetween(0, slot_count()); }
  // ε_p: over the slots observed since the last update (all of them before the first).
  Error PredictionError() const { return ErrorBetween(update_slot_, slot_count()); }

  // Sizes behind eq. 16's compression ratio r = m·n / z for this state (n = 1).
  struct Compression {
    size_t model_bytes = 0;     // P, encoded
    size_t outlier_bytes = 0;   // O, encoded
    size_t coverage_bytes = 0;  // the coverage, encoded (the paper's data had no gaps)
    size_t record_bytes = 0;    // the whole encoded record
    uint64_t raw_bits = 0;      // m slots at one bit each
    // m / (bits of P + O).
    double ratio() const;
  };
  Compression CompressionFigures() const;

  // The record: version byte, t0 and Δ (little-endian doubles), update slot, P, coverage, O.
  void EncodeTo(std::string* out) const;
  std::string Encode() const;
  size_t encoded_size() const;
  // DataLoss naming the field on truncated, corrupted or inconsistent bytes.
  static absl::StatusOr<LosslessHistory> Decode(std::string_view bytes);

  bool operator==(const LosslessHistory&) const = default;

 private:
  LosslessHistory(double t0, double delta) : t0_(t0), delta_(delta) {}
  // The value every observed slot holds, when P's estimate is the same at every slot and O marks none
  // or all of the observed slots; nullopt otherwise. O(toggle points).
  std::optional<bool> ConstantSignal() const;
  // Adds to errors[l] the wrong estimates of the published P at order l on the slots observed since
  // the last update (SlotPredictor::CountErrors). `signal` is all m slots, or empty for a constant
  // history: then only what the scores need is reconstructed.
  void ScoreSinceUpdate(std::span<const SlotState> signal, std::span<uint64_t> errors) const;
  // Rebuilds O from scratch against the current P so that `signal` (all m slots) is reproduced.
  void RebuildOutliers(std::span<const SlotState> signal);

  double t0_ = 0;
  double delta_ = 1;
  uint64_t update_slot_ = 0;
  BinModel model_;
  SlotSet coverage_;
  SlotSet outliers_;
};

}  // namespace fremen::model
