// The histogram buckets the metrics share, so that latencies compare across families.
#pragma once

#include <prometheus/histogram.h>

namespace fremen::server {

// Seconds, 100 µs to 30 s in steps of about 2.5: a cached read to a long update job or sync.
inline const prometheus::Histogram::BucketBoundaries& LatencyBuckets() {
  static const prometheus::Histogram::BucketBoundaries kBuckets = {
      0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30};
  return kBuckets;
}

// Counts (records in a group commit), 1 to 4096 in powers of 2.
inline const prometheus::Histogram::BucketBoundaries& CountBuckets() {
  static const prometheus::Histogram::BucketBoundaries kBuckets = {1,   2,   4,    8,    16,   32,  64,
                                                                   128, 256, 512, 1024, 2048, 4096};
  return kBuckets;
}

// Seconds of long work (checkpoints, update jobs): 10 ms to 30 min.
inline const prometheus::Histogram::BucketBoundaries& JobBuckets() {
  static const prometheus::Histogram::BucketBoundaries kBuckets = {0.01, 0.05, 0.1, 0.5, 1, 5, 10, 30, 60, 300, 1800};
  return kBuckets;
}

}  // namespace fremen::server
