#include "storage/model/lossless/slot_estimator.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "storage/model/kernels/cpu_dispatch.h"

namespace fremen::model {

namespace {

// Slots advanced together by the recurrence: two vectors of four doubles (GCC's vector extension,
// so that the portable build gets SSE2 pairs and the AVX2 clone whole vectors).
using Vec = double __attribute__((vector_size(32)));
constexpr size_t kWidth = 4;
constexpr size_t kLanes = 2 * kWidth;
static_assert(SlotEstimator::kChunk % kLanes == 0);

// v[i] += Re(c·e^{jθ(begin + i)}) for i < count (a whole number of groups of kLanes), from
// `seed` = e^{jθ·begin}. Ordinary arithmetic (contraction allowed): only the bound matters.
// Cloned for AVX2 (cpu_dispatch.h).
FREMEN_KERNEL_CLONES void AddApproximate(const BinComponent& c, UnitPhasor seed, UnitPhasor step, UnitPhasor leap,
                                         size_t count, double* v) {
  Vec re[2], im[2];
  double zr = c.a * seed.cos - c.b * seed.sin, zi = c.a * seed.sin + c.b * seed.cos;
  for (size_t l = 0; l < kLanes; ++l) {
    re[l / kWidth][l % kWidth] = zr;
    im[l / kWidth][l % kWidth] = zi;
    const double r = zr * step.cos - zi * step.sin;
    zi = zr * step.sin + zi * step.cos;
    zr = r;
  }
  const Vec wr = {leap.cos, leap.cos, leap.cos, leap.cos}, wi = {leap.sin, leap.sin, leap.sin, leap.sin};
  for (size_t i = 0; i < count; i += kLanes) {
    for (size_t h = 0; h < 2; ++h) {
      Vec x;
      std::memcpy(&x, v + i + h * kWidth, sizeof x);
      x += re[h];
      std::memcpy(v + i + h * kWidth, &x, sizeof x);
      const Vec r = re[h] * wr - im[h] * wi;
      im[h] = re[h] * wi + im[h] * wr;
      re[h] = r;
    }
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
  const size_t whole = (out.size() + kLanes - 1) / kLanes * kLanes;  // whole groups of lanes
  double v[kChunk];
  std::fill(v, v + whole, static_cast<double>(model_.alpha0()));
  for (const Component& c : components_) {
    AddApproximate(c.c, BinPhasor(AngleIndex(c.c.k, begin, n), n), c.step, c.leap, whole, v);
  }
  // Decided by the approximation, branch-free; then the slots too close to call (or not a number),
  // if any, by the record's own arithmetic.
  bool unsure = false;
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = v[i] >= 0.5;
    unsure |= !(std::fabs(v[i] - 0.5) > bound_);
  }
  size_t exact = 0;
  if (!unsure) return exact;
  for (size_t i = 0; i < out.size(); ++i) {
    if (std::fabs(v[i] - 0.5) > bound_) continue;
    out[i] = model_.SlotValue(begin + i) >= 0.5;
    ++exact;
  }
  return exact;
}

}  // namespace fremen::model
