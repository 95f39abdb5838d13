// s'(i) = p(i) ≥ 0.5, eq. 7's estimate from a lossless history's P, over runs of slots: what the
// update's reconstruction and its rebuilt outlier set O need at every slot (docs/performance.md,
// "The lossless night").
//
// p's bits are part of the record format (bin_phasor.h), but only through this threshold. So p is
// first approximated cheaply: each component c·e^{jθi} (c = a + jb) by a phasor recurrence, eight
// slots at a time multiplied by e^{j8θ}, reseeded exactly every kChunk slots; vectorised, about a
// multiply-add per component and slot, against ~20 instructions for SlotPredictor's fixed-rounding
// evaluation. The recurrence drifts by a few ulp per step; |approximation − SlotValue| stays below
// kRelativeBound·(|α0| + Σ|a| + |b|), which is more than a thousand times that drift and the error
// of SlotValue's own phasors. Wherever the approximation is within that bound of 0.5 the slot is
// decided by BinModel::SlotValue itself, so every estimate is exactly SlotValue(i) ≥ 0.5 (tests
// compare them on generated models, crossings of 0.5 and values of exactly 0.5 among them).
// Thread-safety: immutable after construction; keeps a reference to the model.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "storage/model/lossless/bin_model.h"
#include "storage/model/lossless/bin_phasor.h"

namespace fremen::model {

class SlotEstimator {
 public:
  // Slots approximated from one exact seed: the recurrence's drift grows with them.
  static constexpr size_t kChunk = 2048;
  // The bound on the approximation's error, relative to |α0| + Σ(|a| + |b|) of the components used.
  static constexpr double kRelativeBound = 1e-9;

  // At the model's selected order.
  explicit SlotEstimator(const BinModel& model);

  // out[i] = (p(begin + i) ≥ 0.5) = BinModel::SlotValue(begin + i) ≥ 0.5, for any out.size().
  // Returns how many slots were close enough to 0.5 to be evaluated by SlotValue.
  size_t Estimates(uint64_t begin, std::span<bool> out) const;

 private:
  struct Component {
    BinComponent c;
    UnitPhasor step;   // e^{jθ}, θ = 2πk/n: from one slot to the next
    UnitPhasor leap;   // e^{j8θ}: from one group of eight slots to the next
  };
  // Estimates for out.size() ≤ kChunk slots.
  size_t ChunkEstimates(uint64_t begin, std::span<bool> out) const;

  const BinModel& model_;
  std::vector<Component> components_;  // the ones used; none when p is α0 everywhere
  double bound_ = 0;
};

}  // namespace fremen::model
