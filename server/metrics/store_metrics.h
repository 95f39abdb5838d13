// The store's metrics (storage/store_observer.h) as Prometheus families, labelled by map:
//   fremen_ingest_batches_total{map,result}          batches answered: applied, duplicate, refused
//   fremen_ingest_observations_total{map}            observations accepted (durable and applied)
//   fremen_ingest_rejected_observations_total{map}   observations rejected in an accepted batch
//   fremen_log_appends_total{map}                    records appended to the write-ahead log
//   fremen_log_fsyncs_total{map}                     group commits written and fdatasynced
//   fremen_log_fsync_duration_seconds{map}           histogram: write + fdatasync of a group
//   fremen_log_group_records{map}                    histogram: records per group commit
//   fremen_checkpoints_total{map}, fremen_checkpoint_duration_seconds{map} (histogram),
//   fremen_checkpoint_bytes_total{map}               checkpoints written into LMDB
//   fremen_recovery_duration_seconds{map}            the map's last recovery (at open)
// Each map's series are looked up once, when the store opens it (ForMap); from then on the
// store's threads only increment them (atomics; a histogram takes its own short lock per group
// commit or checkpoint, never per observation). A deleted map's series stay until the daemon
// restarts, as counters should.
// Thread-safety: every method may be called from any thread.
#pragma once

#include <prometheus/counter.h>
#include <prometheus/family.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <functional>
#include <memory>
#include <string>

#include "storage/store_observer.h"

namespace fremen::server {

class StoreMetrics final : public storage::StoreObserver {
 public:
  // The families are added to `registry`, which must outlive this and every map's observer.
  // `opened` (may be empty) is told of each map ForMap is asked for.
  StoreMetrics(prometheus::Registry& registry, std::function<void(const std::string&)> opened);

  std::shared_ptr<storage::MapObserver> ForMap(const std::string& map) override;

 private:
  prometheus::Family<prometheus::Counter>& batches_;
  prometheus::Family<prometheus::Counter>& observations_;
  prometheus::Family<prometheus::Counter>& rejected_;
  prometheus::Family<prometheus::Counter>& appends_;
  prometheus::Family<prometheus::Counter>& fsyncs_;
  prometheus::Family<prometheus::Histogram>& fsync_seconds_;
  prometheus::Family<prometheus::Histogram>& group_records_;
  prometheus::Family<prometheus::Counter>& checkpoints_;
  prometheus::Family<prometheus::Histogram>& checkpoint_seconds_;
  prometheus::Family<prometheus::Counter>& checkpoint_bytes_;
  prometheus::Family<prometheus::Gauge>& recovery_seconds_;
  const std::function<void(const std::string&)> opened_;
};

}  // namespace fremen::server
