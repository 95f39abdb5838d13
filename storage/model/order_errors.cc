#include "storage/model/order_errors.h"

#include <cmath>

#include "storage/model/published_model.h"

namespace fremen::model {

void OrderErrors::Add(double t, const double* predictions, float s, ErrorCriterion criterion, double half_life) {
  double w = 1.0;
  if (half_life > 0) {
    if (weight_ == 0) t_ref_ = t;  // nothing to decay yet
    if (t > t_ref_) {
      const double decay = std::exp2(-(t - t_ref_) / half_life);
      for (double& e : errors_) e *= decay;
      weight_ *= decay;
      t_ref_ = t;
    } else {
      w = std::exp2(-(t_ref_ - t) / half_life);
    }
  } else if (t > t_ref_) {
    t_ref_ = t;
  }
  weight_ += w;
  for (size_t l = 0; l < errors_.size(); ++l) {
    const double p = Clamp01(predictions[l]);
    const double e = criterion == ErrorCriterion::kThreshold ? std::fabs((p > 0.5 ? 1.0 : 0.0) - s) : (p - s) * (p - s);
    errors_[l] += w * e;
  }
}

void OrderErrors::Reset() {
  std::fill(errors_.begin(), errors_.end(), 0.0);
  weight_ = 0;
}

}  // namespace fremen::model
