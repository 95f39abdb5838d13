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
// Cost: Stats walks every state of the map under its shards' read locks (as GetMapStats does) —
// about a millisecond per 100k states, so a scrape of a map of 10M states costs ~0.1 s of one
// core and delays the map's writers as little as a GetMapStats does. A daemon of very large maps
// wants a longer scrape_interval (15 s is Prometheus's default, and fine).
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
