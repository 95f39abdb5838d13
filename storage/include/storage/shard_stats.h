// What a shard reports about itself (Shard::Stats), and the sum over a map's shards.
// Thread-safety: a value type.
#pragma once

#include <cstdint>
#include <vector>

namespace fremen::storage {

struct ShardStats {
  uint64_t states = 0;
  uint64_t dynamic_states = 0;
  uint64_t observations = 0;  // Σ n over states
  uint64_t disk_bytes = 0;
  uint64_t memory_bytes = 0;
  uint64_t wide_states = 0;  // dynamic states whose spectrum is folded in double (model/wide_bodies.h)
  std::vector<uint64_t> order_histogram;  // selected order of dynamic published states, 0..L
  double prediction_error_sum = 0;        // Σ ε_p(selected order) over dynamic states with evidence
  uint64_t prediction_error_states = 0;
  // Lossless maps (eq. 15 from the outlier sets): wrong and observed slots, over all history (ε_e)
  // and since the last update (ε_p).
  uint64_t estimation_wrong = 0, estimation_observed = 0;
  uint64_t lossless_prediction_wrong = 0, lossless_prediction_observed = 0;

  // Adds every count of `other`, the order histogram bin by bin (growing to the longer one).
  ShardStats& operator+=(const ShardStats& other);
};

}  // namespace fremen::storage
