#include "client/lib/backoff.h"

#include <algorithm>
#include <cmath>

namespace fremen::client {

Backoff::Backoff(const RetryPolicy& policy, uint64_t seed) : policy_(policy), random_(seed) {}

absl::Duration Backoff::Nominal(const RetryPolicy& policy, int retry) {
  const double multiplier = std::max(1.0, policy.multiplier);
  // Capped exponent: beyond ~60 doublings the cap has long been reached, and pow would overflow.
  const double factor = std::pow(multiplier, std::min(retry, 60));
  const double seconds = absl::ToDoubleSeconds(policy.initial_backoff) * factor;
  return std::min(absl::Seconds(seconds), policy.max_backoff);
}

absl::Duration Backoff::Next() {
  const absl::Duration nominal = Nominal(policy_, retries_++);
  const double jitter = std::clamp(policy_.jitter, 0.0, 0.99);
  if (jitter == 0) return nominal;
  std::uniform_real_distribution<double> scale(1 - jitter, 1 + jitter);
  return nominal * scale(random_);
}

}  // namespace fremen::client
