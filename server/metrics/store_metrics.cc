#include "server/metrics/store_metrics.h"

#include <utility>

#include "server/metrics/buckets.h"

namespace fremen::server {

namespace {

// One map's series, resolved once.
class MapMetrics final : public storage::MapObserver {
 public:
  MapMetrics(prometheus::Counter& applied, prometheus::Counter& duplicate, prometheus::Counter& refused,
             prometheus::Counter& observations, prometheus::Counter& rejected, prometheus::Counter& appends,
             prometheus::Counter& fsyncs, prometheus::Histogram& fsync_seconds, prometheus::Histogram& group_records,
             prometheus::Counter& checkpoints, prometheus::Histogram& checkpoint_seconds,
             prometheus::Counter& checkpoint_bytes, prometheus::Gauge& recovery_seconds)
      : applied_(applied),
        duplicate_(duplicate),
        refused_(refused),
        observations_(observations),
        rejected_(rejected),
        appends_(appends),
        fsyncs_(fsyncs),
        fsync_seconds_(fsync_seconds),
        group_records_(group_records),
        checkpoints_(checkpoints),
        checkpoint_seconds_(checkpoint_seconds),
        checkpoint_bytes_(checkpoint_bytes),
        recovery_seconds_(recovery_seconds) {}

  void BatchAnswered(const storage::BatchAck& ack) override {
    if (!ack.error.ok()) {
      refused_.Increment();
    } else if (ack.duplicate) {
      duplicate_.Increment();
    } else {
      applied_.Increment();
      observations_.Increment(static_cast<double>(ack.accepted));
      rejected_.Increment(static_cast<double>(ack.rejected));
    }
  }
  void LogSynced(uint64_t records, absl::Duration took) override {
    appends_.Increment(static_cast<double>(records));
    fsyncs_.Increment();
    fsync_seconds_.Observe(absl::ToDoubleSeconds(took));
    group_records_.Observe(static_cast<double>(records));
  }
  void Checkpointed(uint64_t bytes, absl::Duration took) override {
    checkpoints_.Increment();
    checkpoint_seconds_.Observe(absl::ToDoubleSeconds(took));
    checkpoint_bytes_.Increment(static_cast<double>(bytes));
  }
  void Recovered(absl::Duration took) override { recovery_seconds_.Set(absl::ToDoubleSeconds(took)); }

 private:
  prometheus::Counter &applied_, &duplicate_, &refused_, &observations_, &rejected_, &appends_, &fsyncs_;
  prometheus::Histogram &fsync_seconds_, &group_records_;
  prometheus::Counter& checkpoints_;
  prometheus::Histogram& checkpoint_seconds_;
  prometheus::Counter& checkpoint_bytes_;
  prometheus::Gauge& recovery_seconds_;
};

prometheus::Family<prometheus::Counter>& Counter(prometheus::Registry& registry, const char* name, const char* help) {
  return prometheus::BuildCounter().Name(name).Help(help).Register(registry);
}

prometheus::Family<prometheus::Histogram>& Histogram(prometheus::Registry& registry, const char* name,
                                                     const char* help) {
  return prometheus::BuildHistogram().Name(name).Help(help).Register(registry);
}

}  // namespace

StoreMetrics::StoreMetrics(prometheus::Registry& registry, std::function<void(const std::string&)> opened)
    : batches_(Counter(registry, "fremen_ingest_batches_total",
                       "Ingest batches answered by the store, by map and result (applied, duplicate, refused)")),
      observations_(Counter(registry, "fremen_ingest_observations_total",
                            "Observations accepted (durable and applied), by map")),
      rejected_(Counter(registry, "fremen_ingest_rejected_observations_total",
                        "Observations rejected within accepted batches (bad cell, value or label), by map")),
      appends_(Counter(registry, "fremen_log_appends_total", "Records appended to the write-ahead log, by map")),
      fsyncs_(Counter(registry, "fremen_log_fsyncs_total", "Group commits written and fdatasynced, by map")),
      fsync_seconds_(Histogram(registry, "fremen_log_fsync_duration_seconds",
                               "Time to write and fdatasync one group commit, by map")),
      group_records_(Histogram(registry, "fremen_log_group_records", "Records per group commit, by map")),
      checkpoints_(Counter(registry, "fremen_checkpoints_total", "Checkpoints written into LMDB, by map")),
      checkpoint_seconds_(Histogram(registry, "fremen_checkpoint_duration_seconds",
                                    "Time to write one checkpoint into LMDB, by map")),
      checkpoint_bytes_(Counter(registry, "fremen_checkpoint_bytes_total",
                                "Bytes of records checkpoints wrote into LMDB, by map")),
      recovery_seconds_(prometheus::BuildGauge()
                            .Name("fremen_recovery_duration_seconds")
                            .Help("Duration of the map's last recovery (checkpoint load and log replay), by map")
                            .Register(registry)),
      opened_(std::move(opened)) {}

std::shared_ptr<storage::MapObserver> StoreMetrics::ForMap(const std::string& map) {
  if (opened_) opened_(map);
  const prometheus::Labels labels = {{"map", map}};
  const auto with = [&](const char* result) {
    return prometheus::Labels{{"map", map}, {"result", result}};
  };
  return std::make_shared<MapMetrics>(
      batches_.Add(with("applied")), batches_.Add(with("duplicate")), batches_.Add(with("refused")),
      observations_.Add(labels), rejected_.Add(labels), appends_.Add(labels), fsyncs_.Add(labels),
      fsync_seconds_.Add(labels, LatencyBuckets()), group_records_.Add(labels, CountBuckets()),
      checkpoints_.Add(labels), checkpoint_seconds_.Add(labels, JobBuckets()), checkpoint_bytes_.Add(labels),
      recovery_seconds_.Add(labels));
}

}  // namespace fremen::server
