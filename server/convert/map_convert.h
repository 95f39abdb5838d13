// fremen.v1.Map ↔ storage::MapInfo. From the proto: the rules only the proto has (kind set, a grid
// exactly for a grid map, known enum values), the defaults of unset optional fields, then storage's
// own validation — its messages renamed to the proto's fields ("map.error_half_life_seconds ..."),
// so that a client is told the field it sent.
// Pure functions; thread-safe.
#pragma once

#include "absl/status/statusor.h"
#include "fremen/v1/maps.pb.h"
#include "storage/map_info.h"
#include "storage/map_store.h"
#include "storage/store.h"

namespace fremen::server {

// InvalidArgument naming the field, as "map.<field>".
absl::StatusOr<storage::MapInfo> MapInfoFromProto(const v1::Map& map);

// Every field set, defaults included.
void MapInfoToProto(const storage::MapInfo& info, v1::Map& out);

// A map's move state (docs/fleet.md, "Moving a map").
v1::MapMoveState MoveStateToProto(storage::MoveState state);
// Sets `map`'s output-only move_state and moved_to from its open store in `store` (a failed map has
// none to tell: left unset).
void AddMoveState(const storage::Store& store, v1::Map& map);

// A storage validation error with storage's field names replaced by the proto's.
absl::Status RenameStorageFields(const absl::Status& status);

}  // namespace fremen::server
