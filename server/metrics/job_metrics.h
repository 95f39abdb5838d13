// The update jobs' metrics (server/jobs/operations.h):
//   fremen_update_jobs_total{result}           jobs ended: ok, cancelled, failed
//   fremen_update_job_duration_seconds         histogram of the successful jobs' durations
//   fremen_update_states_published_total       states the successful jobs published
// counted by Finished, the registry's on_finished hook; and at scrape time (JobProgressCollector):
//   fremen_update_jobs_active                  jobs queued or running
//   fremen_update_job_progress_ratio{map}      the publishing job's states done over its total
// Thread-safety: every method may be called from any thread.
#pragma once

#include <prometheus/collectable.h>
#include <prometheus/counter.h>
#include <prometheus/family.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <vector>

#include "server/jobs/operations.h"

namespace fremen::server {

class JobMetrics {
 public:
  // The families are added to `registry`, which must outlive this.
  explicit JobMetrics(prometheus::Registry& registry);

  // An operation ended (OperationRegistry::Options::on_finished).
  void Finished(const OperationView& operation);

 private:
  prometheus::Family<prometheus::Counter>& jobs_;
  prometheus::Histogram& duration_;
  prometheus::Counter& states_published_;
};

class JobProgressCollector final : public prometheus::Collectable {
 public:
  // `registry` must outlive this.
  explicit JobProgressCollector(const OperationRegistry* registry) : registry_(registry) {}

  std::vector<prometheus::MetricFamily> Collect() const override;

 private:
  const OperationRegistry* registry_;
};

}  // namespace fremen::server
