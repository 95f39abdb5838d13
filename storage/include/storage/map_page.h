// One page of a store's map list (Store::ListMaps), and the catalog records met on the way that
// did not verify.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "storage/map_info.h"

namespace fremen::storage {

// A catalog record that did not verify or decode.
struct DamagedCatalogEntry {
  std::string key;      // the stored name (itself possibly damaged)
  absl::Status status;  // DataLoss naming the file and key
};

struct MapPage {
  std::vector<MapInfo> maps;
  // Pass to the next List call; empty on the last page.
  std::string next_page_token;
  // Damaged records met while listing this page, in key order; not in `maps`.
  std::vector<DamagedCatalogEntry> damaged;
};

inline constexpr size_t kMaxPageSize = 1000;
inline constexpr size_t kDefaultPageSize = 100;

}  // namespace fremen::storage
