#include "storage/model/state_model.h"

#include <algorithm>
#include <vector>

namespace fremen::model {

template <typename Real>
BasicStateModel<Real>::BasicStateModel(const ModelSettings& settings)
    : settings_(&settings), spectrum_(settings.periods.size()), errors_(settings.max_order) {}

template <typename Real>
void BasicStateModel<Real>::Score(const PhasorTable& phasors, float s) {
  // A state never published is not scored: "the model" it would be scored against (its running
  // mean) changes with every observation, which would make the counters depend on batching.
  if (!has_published_) return;
  double predictions[kMaxMaxOrder + 1];
  published_.PredictAllOrders(phasors, settings_->max_order, predictions);
  errors_.Add(phasors.time(), predictions, s, settings_->criterion, settings_->error_half_life);
}

template <typename Real>
void BasicStateModel<Real>::Observe(const PhasorTable& phasors, float s) {
  Score(phasors, s);
  spectrum_.Observe(ScanPhasors<Real>(phasors), s);
  persistence_.Observe(phasors.time(), s);
}

template <typename Real>
void BasicStateModel<Real>::AddBatch(std::span<const Observation> observations) {
  std::vector<Observation> sorted(observations.begin(), observations.end());
  // Stable, so that equal times keep their given order (the later one is the newest value).
  std::stable_sort(sorted.begin(), sorted.end(), [](const Observation& a, const Observation& b) { return a.t < b.t; });
  for (const Observation& o : sorted) {
    if (has_published_) Score(PhasorTable(settings_->periods, o.t), o.s);
    persistence_.Observe(o.t, o.s);
  }
  spectrum_.AddBatch(sorted, settings_->periods);
}

template <typename Real>
int BasicStateModel<Real>::Update() {
  const int order = errors_.BestOrder(settings_->order_rule);
  Publish(order);
  return order;
}

template <typename Real>
void BasicStateModel<Real>::Publish(int order) {
  published_ = PublishedModel::FromSpectrum(spectrum_, settings_->periods, settings_->max_order, order);
  has_published_ = true;
  if (settings_->error_half_life == 0) errors_.Reset();
}

template <typename Real>
double BasicStateModel<Real>::Predict(const PhasorTable& phasors, bool with_persistence, int order) const {
  const double p = has_published_ ? published_.Predict(phasors, order) : spectrum_.gamma0();
  return with_persistence && settings_->persistence ? persistence_.Predict(phasors.time(), p) : p;
}

template <typename Real>
double BasicStateModel<Real>::Predict(double t, bool with_persistence, int order) const {
  return Predict(PhasorTable(settings_->periods, t), with_persistence, order);
}

template class BasicStateModel<float>;
template class BasicStateModel<double>;

}  // namespace fremen::model
