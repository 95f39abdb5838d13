#include "server/metrics/family_builder.h"

#include <utility>

namespace fremen::server {

size_t FamilyBuilder::Declare(const std::string& name, const std::string& help, prometheus::MetricType type) {
  prometheus::MetricFamily family;
  family.name = name;
  family.help = help;
  family.type = type;
  families_.push_back(std::move(family));
  return families_.size() - 1;
}

void FamilyBuilder::Add(size_t family_index, const std::map<std::string, std::string>& labels, double value) {
  prometheus::MetricFamily* family = &families_.at(family_index);
  prometheus::ClientMetric sample;
  for (const auto& [label, text] : labels) sample.label.push_back({label, text});
  if (family->type == prometheus::MetricType::Counter) {
    sample.counter.value = value;
  } else {
    sample.gauge.value = value;
  }
  family->metric.push_back(std::move(sample));
}

std::vector<prometheus::MetricFamily> FamilyBuilder::Take() { return std::move(families_); }

}  // namespace fremen::server
