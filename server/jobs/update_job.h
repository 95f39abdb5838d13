// The update job over the store, and the daemon's update machinery built from it.
//
// The job of one map (docs/update-job.md): the map's statistics before, the publication — every
// dynamic state observed since its last update has its order chosen by its decayed prequential error
// and its P republished (lossless maps: its history re-transformed, O rebuilt), one record
// of the map's log so that recovery repeats it (storage::MapStore::PublishModels) — and the
// statistics after, which give the operation's figures (ε_p before/after, order histogram), also
// kept as the map's UpdateRecord (storage::MapStore::RecordUpdate) for its statistics.
// The schedule: an UpdateScheduler over every map of the store that starts operations.
// Thread-safety: a job runs on the operation registry's thread; it only reads `store`.
#pragma once

#include <memory>

#include "absl/status/statusor.h"
#include "server/jobs/clock.h"
#include "server/daemon/config.h"
#include "server/jobs/operations.h"
#include "server/rpc/store_handle.h"
#include "server/jobs/update_scheduler.h"

namespace fremen::server {

// `store` must outlive every job run.
UpdateJob StoreUpdateJob(const StoreHandle* store);

// The scheduler of the config's update_schedule over every map of `store`, starting updates in
// `operations` (not started: call Start() once the store is open). Everything must outlive it.
absl::StatusOr<std::unique_ptr<UpdateScheduler>> NewStoreUpdateScheduler(const ServerConfig& config,
                                                                         const Clock& clock,
                                                                         const StoreHandle* store,
                                                                         OperationRegistry* operations);

}  // namespace fremen::server
