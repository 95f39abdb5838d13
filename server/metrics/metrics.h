// The daemon's metrics: one Prometheus registry, the observers the RPC layer, the store and the
// update jobs report to, and the scrape-time collectors; Scrape() renders them all in the
// Prometheus text format for GET /metrics (metrics_route.h). docs/http.md, "Metrics", lists them
// with where each is counted.
// Lifetime: the daemon owns one; it outlives the gRPC server, the store and the HTTP port.
// Thread-safety: the observers and Scrape may be used from any thread; Watch once, before the
// first Scrape.
#pragma once

#include <prometheus/registry.h>

#include <memory>
#include <string>
#include <vector>

#include "server/jobs/operations.h"
#include "server/metrics/call_metrics.h"
#include "server/metrics/job_metrics.h"
#include "server/metrics/map_collector.h"
#include "server/metrics/store_metrics.h"
#include "server/rpc/store_handle.h"

namespace fremen::server {

class Metrics {
 public:
  Metrics();

  CallObserver* calls() { return &calls_; }
  storage::StoreObserver* store() { return &store_; }
  JobMetrics* jobs() { return &jobs_; }

  // Exports, at each scrape, the maps of `store` and the running jobs of `operations` (each may be
  // null: not exported). Both must outlive this.
  void Watch(const StoreHandle* store, const OperationRegistry* operations);

  // Every metric family, as a scrape sees them.
  std::vector<prometheus::MetricFamily> Collect() const;
  // Collect() in the Prometheus text format (version 0.0.4).
  std::string Scrape() const;

 private:
  std::shared_ptr<prometheus::Registry> registry_;
  CallMetrics calls_;
  StoreMetrics store_;
  JobMetrics jobs_;
  std::unique_ptr<MapCollector> maps_;
  std::unique_ptr<JobProgressCollector> progress_;
};

}  // namespace fremen::server
