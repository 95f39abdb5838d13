#include "server/metrics/job_metrics.h"

#include "server/metrics/buckets.h"
#include "server/metrics/family_builder.h"

namespace fremen::server {

JobMetrics::JobMetrics(prometheus::Registry& registry)
    : jobs_(prometheus::BuildCounter()
                .Name("fremen_update_jobs_total")
                .Help("Update jobs ended, by result (ok, cancelled, failed)")
                .Register(registry)),
      duration_(prometheus::BuildHistogram()
                    .Name("fremen_update_job_duration_seconds")
                    .Help("Durations of the update jobs that succeeded, from running to done")
                    .Register(registry)
                    .Add({}, JobBuckets())),
      states_published_(prometheus::BuildCounter()
                            .Name("fremen_update_states_published_total")
                            .Help("States the successful update jobs published")
                            .Register(registry)
                            .Add({})) {
  for (const char* result : {"ok", "cancelled", "failed"}) jobs_.Add({{"result", result}});  // exported from 0
}

void JobMetrics::Finished(const OperationView& operation) {
  const char* result = operation.error.ok() ? "ok" : absl::IsCancelled(operation.error) ? "cancelled" : "failed";
  jobs_.Add({{"result", result}}).Increment();
  if (!operation.result.has_value()) return;
  duration_.Observe(absl::ToDoubleSeconds(operation.result->duration));
  states_published_.Increment(static_cast<double>(operation.result->states_published));
}

std::vector<prometheus::MetricFamily> JobProgressCollector::Collect() const {
  FamilyBuilder out;
  const size_t active = out.Declare("fremen_update_jobs_active", "Update jobs queued or running",
                                    prometheus::MetricType::Gauge);
  const size_t progress = out.Declare("fremen_update_job_progress_ratio",
                                      "States the publishing update job has done over its total, by map",
                                      prometheus::MetricType::Gauge);
  out.Add(active, {}, static_cast<double>(registry_->running()));
  // Running jobs are few (at most one per map), so one page holds them.
  auto page = registry_->List("", /*running_only=*/true, 1000, "");
  if (page.ok()) {
    for (const OperationView& operation : page->operations) {
      if (operation.stage != OperationStage::kPublishing || operation.states_total == 0) continue;
      out.Add(progress, {{"map", operation.map}},
              static_cast<double>(operation.states_done) / static_cast<double>(operation.states_total));
    }
  }
  return out.Take();
}

}  // namespace fremen::server
