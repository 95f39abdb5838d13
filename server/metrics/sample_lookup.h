// For tests: the value of one sample among collected families, found by family name and exact
// labels, so that a test reads what a scrape would show without parsing the text format.
// Thread-safety: a pure function.
#pragma once

#include <prometheus/metric_family.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace fremen::server {

using SampleLabels = std::map<std::string, std::string>;

// The value of the sample of family `name` whose labels are exactly `labels` (a histogram: its
// count); nullopt when there is none.
inline std::optional<double> Sample(const std::vector<prometheus::MetricFamily>& families, const std::string& name,
                                    const SampleLabels& labels = {}) {
  for (const prometheus::MetricFamily& family : families) {
    if (family.name != name) continue;
    for (const prometheus::ClientMetric& metric : family.metric) {
      SampleLabels have;
      for (const auto& label : metric.label) have[label.name] = label.value;
      if (have != labels) continue;
      switch (family.type) {
        case prometheus::MetricType::Counter: return metric.counter.value;
        case prometheus::MetricType::Gauge: return metric.gauge.value;
        case prometheus::MetricType::Histogram: return static_cast<double>(metric.histogram.sample_count);
        default: return std::nullopt;
      }
    }
  }
  return std::nullopt;
}

}  // namespace fremen::server
