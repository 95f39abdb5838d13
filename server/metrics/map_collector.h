// The per-map gauges, computed when Prometheus scrapes: for each open map, what GetMapStats
// answers (MapStore::Stats, the same figures), and the count of failed maps.
//   fremen_map_states, fremen_map_dynamic_states, fremen_map_observations{map}
//   fremen_map_memory_bytes, fremen_map_disk_bytes, fremen_map_log_bytes{map}
//   fremen_map_prediction_error{map}     mean ε_p over dynamic states with evidence
//   fremen_map_compression_ratio{map}    raw observation bits over model bytes
//   fremen_ingest_queued_observations{map}  submitted, not yet taken by the committer
//   fremen_lmdb_map_size_bytes, fremen_lmdb_readers{map}, fremen_lmdb_growths_total{map}
//   fremen_maps (open maps), fremen_failed_maps (maps that did not open; their reasons are in
//   GetServerStatus and the log: a reason label would make a series per message)
// Cost: Stats walks every state of the map under its shards' read locks (as GetMapStats does):
// a scrape costs one GetMapStats per map, linear in the states. A daemon of very large maps wants
// a longer scrape_interval rather than a shorter one (docs/http.md, "What a scrape costs").
// While the store is being recovered there are no maps yet: only fremen_maps 0 is exported.
// Thread-safety: Collect may be called from any thread.
#pragma once

#include <prometheus/collectable.h>
#include <prometheus/metric_family.h>

#include <vector>

#include "server/rpc/store_handle.h"

namespace fremen::server {

class MapCollector final : public prometheus::Collectable {
 public:
  // `store` must outlive this.
  explicit MapCollector(const StoreHandle* store) : store_(store) {}

  std::vector<prometheus::MetricFamily> Collect() const override;

 private:
  const StoreHandle* store_;
};

}  // namespace fremen::server
