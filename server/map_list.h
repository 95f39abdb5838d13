// Every map of the store, page by page: for the update schedule (which maps to update) and the
// server status (how many maps and states).
// Thread-safety: as storage::Store.
#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "storage/store.h"

namespace fremen::server {

absl::StatusOr<std::vector<storage::MapInfo>> ListAllMaps(const storage::Store& store);

}  // namespace fremen::server
