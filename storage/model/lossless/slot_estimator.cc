#include "storage/model/lossless/slot_estimator.h"

#include <algorithm>
#include <cmath>

#include "storage/model/kernels/cpu_dispatch.h"

namespace fremen::model {

namespace {

// Slots advanced together by the recurrence: one vector multiply per component and group.
constexpr size_t kLanes = 8;
static_assert(SlotEstimator::kChunk % kLanes == 0);

// The product of two phasors in ordinary arithmetic (contraction allowed: only the bound matters).
inline void Multiply(double& re, double& im, double wr, double wi) {
  const double r = re * wr - im * wi;
  im = re * wi + im * wr;
  re = r;
}

// v[i] += Re(c·e^{jθ(begin + i)}) for i < count (rounded up to whole groups of kLanes; v holds them),
// from `seed` = e^{jθ·begin}. Cloned for AVX2 (cpu_dispatch.h): the lanes are one vector.
FREMEN_KERNEL_CLONES void AddApproximate(const BinComponent& c, UnitPhasor seed, UnitPhasor step, UnitPhasor leap,
                                         size_t count, double* v) {
  double re[kLanes], im[kLanes];
  double zr = c.a * seed.cos - c.b * seed.sin, zi = c.a * seed.sin + c.b * seed.cos;
  for (size_t l = 0; l < kLanes; ++l) {
    re[l] = zr;
    im[l] = zi;
    Multiply(zr, zi, step.cos, step.sin);
  }
  for (size_t i = 0; i < count; i += kLanes) {
    for (size_t l = 0; l < kLanes; ++l) v[i + l] += re[l];
    for (size_t l = 0; l < kLanes; ++l) Multiply(re[l], im[l], leap.cos, leap.sin);
  }
}

// k·slot mod n, the angle index of bin k at `slot` (as BinModel's). k < n < 2^32.
uint64_t AngleIndex(uint64_t k, uint64_t slot, uint64_t n) { return k * (slot % n) % n; }

}  // namespace

SlotEstimator::SlotEstimator(const BinModel& model) : model_(model) {
  if (model.IsConstant()) return;  // p = α0 at every slot
  const uint64_t n = model.length();
  double scale = std::fabs(static_cast<double>(model.alpha0()));
  for (int j = 0; j < model.order(); ++j) {
    const BinComponent& c = model.components()[j];
    components_.push_back({c, BinPhasor(c.k, n), BinPhasor(AngleIndex(c.k, kLanes, n), n)});
    scale += std::fabs(static_cast<double>(c.a)) + std::fabs(static_cast<double>(c.b));
  }
  bound_ = kRelativeBound * scale;
}

size_t SlotEstimator::Estimates(uint64_t begin, std::span<bool> out) const {
  if (components_.empty()) {
    std::fill(out.begin(), out.end(), model_.alpha0() >= 0.5f);
    return 0;
  }
  size_t exact = 0;
  for (size_t at = 0; at < out.size(); at += kChunk) {
    exact += ChunkEstimates(begin + at, out.subspan(at, std::min(kChunk, out.size() - at)));
  }
  return exact;
}

size_t SlotEstimator::ChunkEstimates(uint64_t begin, std::span<bool> out) const {
  const uint64_t n = model_.length();
  const size_t groups = (out.size() + kLanes - 1) / kLanes * kLanes;
  double v[kChunk];
  std::fill(v, v + groups, static_cast<double>(model_.alpha0()));
  for (const Component& c : components_) {
    AddApproximate(c.c, BinPhasor(AngleIndex(c.c.k, begin, n), n), c.step, c.leap, groups, v);
  }
  size_t exact = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    const double d = v[i] - 0.5;
    if (d > bound_) {
      out[i] = true;
    } else if (d < -bound_) {
      out[i] = false;
    } else {  // too close to call (or not a number): the record's own arithmetic decides
      out[i] = model_.SlotValue(begin + i) >= 0.5;
      ++exact;
    }
  }
  return exact;
}

}  // namespace fremen::model
