// Every map of the store, page by page: for the update schedule (which maps to update), the
// background scrub (which maps to verify) and the server status (how many maps and states).
// Thread-safety: as storage::Store.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/rpc/store_handle.h"
#include "storage/store.h"

namespace fremen::server {

absl::StatusOr<std::vector<storage::MapInfo>> ListAllMaps(const storage::Store& store);
// The names of every map of the store once it is open (Unavailable while it is recovered).
absl::StatusOr<std::vector<std::string>> ListAllMapNames(const StoreHandle& store);

}  // namespace fremen::server
