// The states a query names (fremen.v1.StateRefs / StateRef) → storage keys: grid cells by index or
// metric point (Morton keys of the map's grid), generic states by id or by name (the stable hash of
// storage/state_names.h). Errors name the field: INVALID_ARGUMENT for a malformed list (none or
// several lists set, lengths that differ, a non-finite point, an empty name), FAILED_PRECONDITION
// for a kind of reference the map's kind does not have (cells of a generic map, ids of a grid),
// OUT_OF_RANGE for a cell or point outside the grid, naming its index ("states.cells[3]").
// Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "fremen/v1/common.pb.h"
#include "storage/map_info.h"

namespace fremen::server {

// How many states `refs` names (the longest of its lists), before any check: cheap, for sizing.
uint64_t RefCount(const v1::StateRefs& refs);

// The keys of the states, in order. `field` names refs in errors ("states").
absl::StatusOr<std::vector<uint64_t>> KeysOfRefs(const storage::MapInfo& map, const v1::StateRefs& refs,
                                                 absl::string_view field);

// The key of one state. InvalidArgument when no reference is set.
absl::StatusOr<uint64_t> KeyOfRef(const storage::MapInfo& map, const v1::StateRef& ref, absl::string_view field);

}  // namespace fremen::server
