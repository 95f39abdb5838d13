#include "server/metrics/metrics.h"

#include <prometheus/text_serializer.h>

#include <iterator>
#include <vector>

namespace fremen::server {

Metrics::Metrics()
    : registry_(std::make_shared<prometheus::Registry>()),
      calls_(*registry_),
      store_(*registry_, [this](const std::string& map) { calls_.MapOpened(map); }),
      jobs_(*registry_) {}

void Metrics::Watch(const StoreHandle* store, const OperationRegistry* operations) {
  if (store != nullptr) maps_ = std::make_unique<MapCollector>(store);
  if (operations != nullptr) progress_ = std::make_unique<JobProgressCollector>(operations);
}

std::vector<prometheus::MetricFamily> Metrics::Collect() const {
  std::vector<prometheus::MetricFamily> families = registry_->Collect();
  const prometheus::Collectable* collectors[] = {maps_.get(), progress_.get()};
  for (const prometheus::Collectable* collector : collectors) {
    if (collector == nullptr) continue;
    std::vector<prometheus::MetricFamily> more = collector->Collect();
    families.insert(families.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
  }
  return families;
}

std::string Metrics::Scrape() const { return prometheus::TextSerializer().Serialize(Collect()); }

}  // namespace fremen::server
