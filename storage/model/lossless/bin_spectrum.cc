#include "storage/model/lossless/bin_spectrum.h"

#include <fftw3.h>

#include <algorithm>
#include <type_traits>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "base/mutex.h"

namespace fremen::model {

namespace {

using Plan = std::shared_ptr<std::remove_pointer_t<fftw_plan>>;

// The FFTW planner (plan creation and destruction) is not thread-safe: every planner call holds mu.
// Lengths differ from state to state, so only the most recently used few plans are kept.
struct PlanCache {
  static constexpr size_t kMaxPlans = 16;
  base::Mutex mu;
  std::vector<std::pair<int, Plan>> plans ABSL_GUARDED_BY(mu);  // most recently used last
};

PlanCache& Cache() {
  static PlanCache* cache = new PlanCache;  // never destroyed: plans may outlive static destruction
  return *cache;
}

// An in-place r2c plan of length n. `buffer` (from fftw_malloc, 2(n/2+1) doubles) is only used to
// plan: FFTW_ESTIMATE does not touch it, and a plan made on an fftw_malloc'd buffer runs on any other
// fftw_malloc'd buffer of the same length (same alignment).
Plan InPlaceR2cPlan(int n, double* buffer) {
  PlanCache& cache = Cache();
  Plan evicted;  // released after the lock: its deleter takes the lock
  base::MutexLock lock(&cache.mu);
  auto it = std::find_if(cache.plans.begin(), cache.plans.end(), [n](const auto& e) { return e.first == n; });
  if (it != cache.plans.end()) {
    std::rotate(it, it + 1, cache.plans.end());
    return cache.plans.back().second;
  }
  Plan plan(fftw_plan_dft_r2c_1d(n, buffer, reinterpret_cast<fftw_complex*>(buffer), FFTW_ESTIMATE),
            [](fftw_plan p) {
              base::MutexLock l(&Cache().mu);
              fftw_destroy_plan(p);
            });
  if (cache.plans.size() == PlanCache::kMaxPlans) {
    evicted = std::move(cache.plans.front().second);
    cache.plans.erase(cache.plans.begin());
  }
  cache.plans.emplace_back(n, plan);
  return plan;
}

}  // namespace

void SlotSpectrum::FftwFree::operator()(double* p) const { fftw_free(p); }

SlotSpectrum SlotSpectrum::Compute(std::span<const SlotState> signal) {
  SlotSpectrum spectrum;
  const size_t n = signal.size();
  spectrum.length_ = n;
  uint64_t ones = 0;
  for (SlotState s : signal) {
    spectrum.observed_ += s != SlotState::kUnobserved;
    ones += s == SlotState::kOccupied;
  }
  const double mean = spectrum.observed_ > 0 ? static_cast<double>(ones) / spectrum.observed_ : 0.0;
  spectrum.gamma0_ = mean;
  // A signal constant wherever it was observed (most cells of a building: walls, floor) is all zeros
  // once its mean is removed, and so is its transform: the FFT, most of such a cell's update, is
  // skipped, and no bins are held. Every bin reads +0.0 (FFTW's own zeros would carry arbitrary
  // signs), so the model's zero-amplitude components have phase 0.
  if (ones == 0 || ones == spectrum.observed_) {
    spectrum.all_zero_ = true;
    return spectrum;
  }
  spectrum.data_.reset(static_cast<double*>(fftw_malloc(sizeof(double) * 2 * (n / 2 + 1))));
  double* data = spectrum.data_.get();
  // Mean removed before the transform rather than after: the same spectrum for k ≥ 1 (a constant has
  // no power there), and a gap filled with 0 instead of γ0 then contributes exactly nothing.
  for (size_t i = 0; i < n; ++i) {
    switch (signal[i]) {
      case SlotState::kFree:
        data[i] = -mean;
        break;
      case SlotState::kOccupied:
        data[i] = 1.0 - mean;
        break;
      default:
        data[i] = 0.0;
    }
  }
  const Plan plan = InPlaceR2cPlan(static_cast<int>(n), data);
  fftw_execute_dft_r2c(plan.get(), data, reinterpret_cast<fftw_complex*>(data));
  return spectrum;
}

SlotSpectrum SlotSpectrum::Constant(size_t n, uint64_t observed, bool value) {
  SlotSpectrum spectrum;
  spectrum.length_ = n;
  spectrum.observed_ = observed;
  spectrum.gamma0_ = value ? 1.0 : 0.0;  // ones / observed, exactly
  spectrum.all_zero_ = true;
  return spectrum;
}

std::complex<double> SlotSpectrum::gamma(size_t k) const {
  if (all_zero_) return 0.0;
  const double scale = 1.0 / static_cast<double>(observed_);
  return {data_[2 * k] * scale, data_[2 * k + 1] * scale};
}

}  // namespace fremen::model
