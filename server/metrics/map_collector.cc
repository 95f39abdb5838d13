#include "server/metrics/map_collector.h"

#include <map>
#include <string>

#include "server/jobs/map_list.h"
#include "server/metrics/family_builder.h"

namespace fremen::server {

std::vector<prometheus::MetricFamily> MapCollector::Collect() const {
  using prometheus::MetricType;
  FamilyBuilder out;
  const size_t maps = out.Declare("fremen_maps", "Maps served (open)", MetricType::Gauge);
  const size_t failed = out.Declare("fremen_failed_maps", "Maps of the catalog that did not open and are not served",
                                    MetricType::Gauge);
  const size_t states = out.Declare("fremen_map_states", "States observed at least once", MetricType::Gauge);
  const size_t dynamic = out.Declare("fremen_map_dynamic_states", "States with a dynamic (FreMEn) model",
                                     MetricType::Gauge);
  const size_t observations =
      out.Declare("fremen_map_observations", "Observations the map's states hold", MetricType::Gauge);
  const size_t memory = out.Declare("fremen_map_memory_bytes", "Memory of the map's models", MetricType::Gauge);
  const size_t disk = out.Declare("fremen_map_disk_bytes", "Bytes of the map's models on disk", MetricType::Gauge);
  const size_t log = out.Declare("fremen_map_log_bytes", "Bytes of the map's write-ahead log", MetricType::Gauge);
  const size_t error = out.Declare("fremen_map_prediction_error",
                                   "Mean prediction error (eps_p) over dynamic states with evidence", MetricType::Gauge);
  const size_t ratio = out.Declare("fremen_map_compression_ratio",
                                   "Raw observation bits over the bytes of the models", MetricType::Gauge);
  const size_t queued = out.Declare("fremen_ingest_queued_observations",
                                    "Observations submitted but not yet logged (the queue backpressure bounds)",
                                    MetricType::Gauge);
  const size_t lmdb_size = out.Declare("fremen_lmdb_map_size_bytes", "LMDB map size of the map's shards, summed",
                                       MetricType::Gauge);
  const size_t lmdb_readers = out.Declare("fremen_lmdb_readers", "LMDB reader slots in use in the map's shards",
                                          MetricType::Gauge);
  const size_t lmdb_growths = out.Declare("fremen_lmdb_growths_total",
                                          "Times a write grew an LMDB map of the map's shards", MetricType::Counter);

  auto store = store_->Get();
  if (!store.ok()) {  // recovering: no maps yet
    out.Add(maps, {}, 0);
    return out.Take();
  }
  out.Add(failed, {}, static_cast<double>((*store)->FailedMaps().size()));
  auto infos = ListAllMaps(**store);
  uint64_t open = 0;
  for (const storage::MapInfo& info : infos.ok() ? *infos : std::vector<storage::MapInfo>{}) {
    auto map = (*store)->Map(info.name);
    if (!map.ok()) continue;  // failed (counted above), or deleted since it was listed
    ++open;
    const storage::MapStats stats = (*map)->Stats();
    const std::map<std::string, std::string> labels = {{"map", info.name}};
    out.Add(states, labels, static_cast<double>(stats.totals.states));
    out.Add(dynamic, labels, static_cast<double>(stats.totals.dynamic_states));
    out.Add(observations, labels, static_cast<double>(stats.totals.observations));
    out.Add(memory, labels, static_cast<double>(stats.totals.memory_bytes));
    out.Add(disk, labels, static_cast<double>(stats.totals.disk_bytes));
    out.Add(log, labels, static_cast<double>(stats.log_bytes));
    out.Add(error, labels, stats.mean_prediction_error);
    out.Add(ratio, labels, stats.compression_ratio);
    out.Add(queued, labels, static_cast<double>(stats.queued_observations));
    out.Add(lmdb_size, labels, static_cast<double>(stats.lmdb_map_size_bytes));
    out.Add(lmdb_readers, labels, static_cast<double>(stats.lmdb_readers));
    out.Add(lmdb_growths, labels, static_cast<double>(stats.lmdb_growths));
  }
  out.Add(maps, {}, static_cast<double>(open));
  return out.Take();
}

}  // namespace fremen::server
