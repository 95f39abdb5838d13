// Builds the families a scrape-time collector (prometheus::Collectable) hands back, one sample at a
// time, so that collectors name each metric once and forget prometheus-cpp's structures.
// Thread-safety: a value type.
#pragma once

#include <prometheus/metric_family.h>

#include <map>
#include <string>
#include <vector>

namespace fremen::server {

class FamilyBuilder {
 public:
  // Declares a family (before its samples); `type` is Gauge or Counter. Returns its handle for Add.
  size_t Declare(const std::string& name, const std::string& help, prometheus::MetricType type);
  // A sample of the family `family_index` (Declare's handle); `labels` as name → value.
  void Add(size_t family_index, const std::map<std::string, std::string>& labels, double value);
  // The families declared, in declaration order, each with its samples (possibly none).
  std::vector<prometheus::MetricFamily> Take();

 private:
  std::vector<prometheus::MetricFamily> families_;
};

}  // namespace fremen::server
