#include "storage/model/published_model.h"

#include <algorithm>
#include <cmath>

namespace fremen::model {

double Component::amplitude() const { return std::hypot(static_cast<double>(a), static_cast<double>(b)); }
double Component::phase() const { return std::atan2(static_cast<double>(b), static_cast<double>(a)); }

PublishedModel PublishedModel::MeanOnly(double alpha0) {
  PublishedModel model;
  model.alpha0_ = static_cast<float>(alpha0);
  return model;
}

PublishedModel PublishedModel::Restore(float alpha0, int order, std::vector<Component> components) {
  PublishedModel model;
  model.alpha0_ = alpha0;
  model.order_ = static_cast<uint8_t>(order);
  model.components_ = std::move(components);
  return model;
}

PublishedModel PublishedModel::FromGammas(double gamma0, const std::vector<std::complex<double>>& gammas,
                                          const PeriodSet& periods, double span, int max_order, int order) {
  PublishedModel model = MeanOnly(gamma0);
  model.order_ = static_cast<uint8_t>(order);
  struct Candidate {
    size_t k;
    double magnitude;
  };
  std::vector<Candidate> eligible;
  const double longest_estimable = kSpanGate * span;
  for (size_t k = 0; k < gammas.size(); ++k) {
    if (periods.period(k) > longest_estimable) continue;
    eligible.push_back({k, std::abs(gammas[k])});
  }
  const size_t keep = std::min<size_t>(max_order, eligible.size());
  // Ties broken by the lower index (the longer period), so publication is deterministic.
  std::partial_sort(eligible.begin(), eligible.begin() + keep, eligible.end(),
                    [](const Candidate& x, const Candidate& y) {
                      return x.magnitude != y.magnitude ? x.magnitude > y.magnitude : x.k < y.k;
                    });
  for (size_t j = 0; j < keep; ++j) {
    // One-sided spectrum: amplitude 2|γ|, phase arg γ.
    const std::complex<double> two_gamma = 2.0 * gammas[eligible[j].k];
    model.components_.push_back({static_cast<uint16_t>(eligible[j].k), static_cast<float>(two_gamma.real()),
                                 static_cast<float>(two_gamma.imag())});
  }
  return model;
}

double PublishedModel::Predict(const PhasorTable& phasors, int order) const {
  const size_t used = std::min<size_t>(order < 0 ? order_ : order, components_.size());
  double p = alpha0_;
  for (size_t j = 0; j < used; ++j) {
    const Component& c = components_[j];
    p += c.a * phasors.cos(c.k) - c.b * phasors.sin(c.k);
  }
  return Clamp01(p);
}

void PublishedModel::PredictAllOrders(const PhasorTable& phasors, int max_order, double* out) const {
  double p = alpha0_;
  out[0] = p;
  for (int l = 1; l <= max_order; ++l) {
    if (static_cast<size_t>(l) <= components_.size()) {
      const Component& c = components_[l - 1];
      p += c.a * phasors.cos(c.k) - c.b * phasors.sin(c.k);
    }
    out[l] = p;
  }
}

double Entropy(double p) {
  if (p <= 0 || p >= 1) return 0;
  return -(p * std::log2(p) + (1 - p) * std::log2(1 - p));
}

}  // namespace fremen::model
