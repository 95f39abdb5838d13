#include "server/jobs/update_job.h"

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "server/rpc/logging.h"
#include "server/jobs/map_list.h"

namespace fremen::server {

UpdateJob StoreUpdateJob(const StoreHandle* store) {
  return [store](JobControl& control) -> absl::StatusOr<UpdateFigures> {
    auto opened = store->Get();
    if (!opened.ok()) return opened.status();
    auto map = (*opened)->Map(control.map());
    if (!map.ok()) return map.status();  // deleted since the operation was queued
    const absl::Time start = absl::Now();
    const storage::MapStats before = (*map)->Stats();
    control.Progress(0, before.totals.dynamic_states);
    if (!control.BeginPublishing()) return absl::CancelledError("cancelled before it published");
    auto published = (*map)->PublishModels([&control](uint64_t done, uint64_t total) { control.Progress(done, total); });
    if (!published.ok()) {
      return absl::Status(published.status().code(),
                          absl::StrCat("publishing the models of map ", control.map(), ": ", published.status().message()));
    }
    const storage::MapStats after = (*map)->Stats();
    UpdateFigures figures;
    figures.states_published = *published;
    figures.order_histogram = after.totals.order_histogram;
    figures.prediction_error_before = before.mean_prediction_error;
    figures.prediction_error_after = after.mean_prediction_error;
    // The map's own record, for its statistics across restarts: losing it loses only a report.
    const storage::UpdateRecord record{absl::ToDoubleSeconds(start - absl::UnixEpoch()),
                                       absl::ToDoubleSeconds(absl::Now() - start),
                                       figures.states_published,
                                       figures.prediction_error_before,
                                       figures.prediction_error_after,
                                       figures.order_histogram};
    if (absl::Status kept = (*map)->RecordUpdate(record); !kept.ok()) {
      DaemonLog()->warn("update of map {}: its record for map statistics was not kept: {}", control.map(),
                  std::string(kept.message()));
    }
    return figures;
  };
}

absl::StatusOr<std::unique_ptr<UpdateScheduler>> NewStoreUpdateScheduler(const ServerConfig& config,
                                                                         const Clock& clock,
                                                                         const StoreHandle* store,
                                                                         OperationRegistry* operations) {
  auto options = SchedulerOptionsFromConfig(config);
  if (!options.ok()) return options.status();
  auto list_maps = [store] { return ListAllMapNames(*store); };
  auto trigger = [operations](const std::string& map) {
    // A map whose update still runs keeps that one (StartUpdate answers it): not an error.
    if (auto op = operations->StartUpdate(map, "schedule"); !op.ok()) {
      DaemonLog()->warn("scheduled update of map {} not started: {}", map, std::string(op.status().message()));
    }
  };
  return std::make_unique<UpdateScheduler>(*std::move(options), clock, std::move(list_maps), std::move(trigger));
}

}  // namespace fremen::server
