#include "storage/shard_stats.h"

#include <gtest/gtest.h>

namespace fremen::storage {
namespace {

// Every field, with a distinct value per field, so that a field left out or added twice shows.
ShardStats Distinct(uint64_t base) {
  ShardStats s;
  s.states = base + 1;
  s.dynamic_states = base + 2;
  s.observations = base + 3;
  s.disk_bytes = base + 4;
  s.memory_bytes = base + 5;
  s.wide_states = base + 6;
  s.order_histogram = {base + 7, base + 8, base + 9};
  s.prediction_error_sum = static_cast<double>(base) + 0.5;
  s.prediction_error_states = base + 10;
  s.estimation_wrong = base + 11;
  s.estimation_observed = base + 12;
  s.lossless_prediction_wrong = base + 13;
  s.lossless_prediction_observed = base + 14;
  return s;
}

TEST(ShardStatsTest, SumAddsEveryFieldAndTheHistogramBinByBin) {
  ShardStats sum;
  sum += Distinct(0);
  sum += Distinct(100);
  EXPECT_EQ(sum.states, 1u + 101);
  EXPECT_EQ(sum.dynamic_states, 2u + 102);
  EXPECT_EQ(sum.observations, 3u + 103);
  EXPECT_EQ(sum.disk_bytes, 4u + 104);
  EXPECT_EQ(sum.memory_bytes, 5u + 105);
  EXPECT_EQ(sum.wide_states, 6u + 106);
  EXPECT_EQ(sum.order_histogram, (std::vector<uint64_t>{7 + 107, 8 + 108, 9 + 109}));
  EXPECT_EQ(sum.prediction_error_sum, 0.5 + 100.5);
  EXPECT_EQ(sum.prediction_error_states, 10u + 110);
  EXPECT_EQ(sum.estimation_wrong, 11u + 111);
  EXPECT_EQ(sum.estimation_observed, 12u + 112);
  EXPECT_EQ(sum.lossless_prediction_wrong, 13u + 113);
  EXPECT_EQ(sum.lossless_prediction_observed, 14u + 114);
}

TEST(ShardStatsTest, AShorterHistogramAddsIntoTheFirstBins) {
  ShardStats sum;
  sum.order_histogram = {1};
  ShardStats longer;
  longer.order_histogram = {1, 2, 3};
  sum += longer;
  EXPECT_EQ(sum.order_histogram, (std::vector<uint64_t>{2, 2, 3}));
  sum += ShardStats{};
  EXPECT_EQ(sum.order_histogram, (std::vector<uint64_t>{2, 2, 3}));
}

}  // namespace
}  // namespace fremen::storage
