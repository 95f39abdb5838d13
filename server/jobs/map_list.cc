#include "server/jobs/map_list.h"

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

absl::StatusOr<std::vector<std::string>> ListAllMapNames(const StoreHandle& store) {
  auto opened = store.Get();
  if (!opened.ok()) return opened.status();
  auto maps = ListAllMaps(**opened);
  if (!maps.ok()) return maps.status();
  std::vector<std::string> names;
  names.reserve(maps->size());
  for (const storage::MapInfo& info : *maps) names.push_back(info.name);
  return names;
}

}  // namespace fremen::server
