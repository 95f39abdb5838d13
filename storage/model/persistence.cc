#include "storage/model/persistence.h"

#include <cmath>

namespace fremen::model {

void Persistence::Observe(double t, float s) {
  if (!observed) {
    observed = 1;
    t_last = t;
    s_last = s;
    return;
  }
  if (t < t_last) return;  // older than the last observation: no time-ordered neighbour to rate against
  if (t == t_last) {       // the same instant seen again: the newest value stands, no rate sample
    s_last = s;
    return;
  }
  const double rate = std::fabs(static_cast<double>(s) - s_last) / (t - t_last);
  samples += 1;
  inv_tau = static_cast<float>(inv_tau + (rate - inv_tau) / samples);
  t_last = t;
  s_last = s;
}

double Persistence::Predict(double t, double p) const {
  if (!observed) return p;
  const double w = std::exp(-std::fabs(t - t_last) * inv_tau);
  return s_last * w + p * (1.0 - w);
}

}  // namespace fremen::model
