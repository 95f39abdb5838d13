// Storage's views of a state and a map → the proto's: StateSnapshot → fremen.v1.StateModel (the
// full model of GetStateModel: spectrum, P, order errors, persistence, the lossless history's
// outlier set and errors) and MapStats → fremen.v1.MapStats.
// Pure functions; thread-safe.
#pragma once

#include <cstdint>

#include "fremen/v1/query.pb.h"
#include "storage/map_info.h"
#include "storage/map_store.h"
#include "storage/model/model_settings.h"
#include "storage/queries.h"

namespace fremen::server {

// Each interval list of a lossless model stops after this many (the message must stay small).
inline constexpr size_t kMaxModelIntervals = 100000;

// The model of the state under `key`. The spectrum (|Ω| components) only when `include_spectrum`.
void StateModelToProto(const storage::MapInfo& map, const model::ModelSettings& settings, uint64_t key,
                       const storage::StateSnapshot& snapshot, bool include_spectrum, v1::StateModel& out);

void MapStatsToProto(const storage::MapStats& stats, v1::MapStats& out);
// A map's last update job (storage/update_record.h), as GetMapStats and GetServerStatus show it.
void UpdateRecordToProto(const storage::UpdateRecord& record, v1::MapUpdate& out);

}  // namespace fremen::server
