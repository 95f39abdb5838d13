#include "server/map_list.h"

namespace fremen::server {

absl::StatusOr<std::vector<storage::MapInfo>> ListAllMaps(const storage::Store& store) {
  std::vector<storage::MapInfo> maps;
  std::string token;
  do {
    auto page = store.ListMaps(storage::kMaxPageSize, token);
    if (!page.ok()) return page.status();
    maps.insert(maps.end(), page->maps.begin(), page->maps.end());
    token = page->next_page_token;
  } while (!token.empty());
  return maps;
}

}  // namespace fremen::server
