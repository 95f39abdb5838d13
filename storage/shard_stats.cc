#include "storage/shard_stats.h"

#include <algorithm>

namespace fremen::storage {

ShardStats& ShardStats::operator+=(const ShardStats& other) {
  states += other.states;
  dynamic_states += other.dynamic_states;
  observations += other.observations;
  disk_bytes += other.disk_bytes;
  memory_bytes += other.memory_bytes;
  wide_states += other.wide_states;
  order_histogram.resize(std::max(order_histogram.size(), other.order_histogram.size()), 0);
  for (size_t l = 0; l < other.order_histogram.size(); ++l) order_histogram[l] += other.order_histogram[l];
  prediction_error_sum += other.prediction_error_sum;
  prediction_error_states += other.prediction_error_states;
  estimation_wrong += other.estimation_wrong;
  estimation_observed += other.estimation_observed;
  lossless_prediction_wrong += other.lossless_prediction_wrong;
  lossless_prediction_observed += other.lossless_prediction_observed;
  return *this;
}

}  // namespace fremen::storage
