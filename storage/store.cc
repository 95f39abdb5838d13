#include "storage/store.h"

#include <sys/stat.h>

#include <filesystem>
#include <set>
#include <fstream>
#include <sstream>
#include <thread>

#include "absl/strings/str_cat.h"
#include "storage/verify.h"

namespace fremen::storage {

namespace fs = std::filesystem;

absl::StatusOr<std::unique_ptr<Store>> Store::Open(const std::string& data_dir, const StoreOptions& options) {
  std::error_code error;
  fs::create_directories(data_dir + "/maps", error);
  if (error) return absl::InternalError(absl::StrCat("cannot create ", data_dir, "/maps: ", error.message()));
  auto catalog = Catalog::Open(data_dir + "/catalog");
  if (!catalog.ok()) return catalog.status();
  StoreOptions resolved = options;
  if (resolved.default_shards == 0) resolved.default_shards = std::max(1u, std::thread::hardware_concurrency());
  auto store = std::unique_ptr<Store>(new Store(data_dir, resolved, *std::move(catalog)));

  std::vector<MapInfo> all;
  std::string token;
  do {
    auto page = store->catalog_->List(kMaxPageSize, token);
    if (!page.ok()) return page.status();
    for (MapInfo& m : page->maps) all.push_back(std::move(m));
    token = page->next_page_token;
  } while (!token.empty());
  std::set<std::string> known;
  for (const MapInfo& info : all) {
    known.insert(std::to_string(info.id));
    auto map = store->OpenMap(info);
    if (!map.ok()) return map.status();
  }
  for (const auto& entry : fs::directory_iterator(data_dir + "/maps", error)) {
    if (!known.contains(entry.path().filename().string())) fs::remove_all(entry.path(), error);
  }
  return store;
}

Store::~Store() { (void)Close(); }

std::string Store::MapDir(uint64_t id) const { return absl::StrCat(data_dir_, "/maps/", id); }

absl::StatusOr<std::shared_ptr<MapStore>> Store::OpenMap(const MapInfo& info) {
  auto map = MapStore::Open(info, MapDir(info.id), options_);
  if (!map.ok()) return map.status();
  std::shared_ptr<MapStore> shared = *std::move(map);
  maps_[info.name] = shared;
  return shared;
}

absl::StatusOr<MapInfo> Store::CreateMap(MapInfo info) {
  std::lock_guard lock(mutex_);
  auto created = catalog_->Create(std::move(info), options_.default_shards);
  if (!created.ok()) return created.status();
  if (auto map = OpenMap(*created); !map.ok()) {
    (void)catalog_->Delete(created->name);
    return map.status();
  }
  return created;
}

absl::StatusOr<MapInfo> Store::GetMap(const std::string& name) const { return catalog_->Get(name); }

absl::StatusOr<MapPage> Store::ListMaps(size_t page_size, const std::string& page_token) const {
  return catalog_->List(page_size, page_token);
}

absl::StatusOr<std::shared_ptr<MapStore>> Store::Map(const std::string& name) const {
  std::lock_guard lock(mutex_);
  auto it = maps_.find(name);
  if (it == maps_.end()) return absl::NotFoundError(absl::StrCat("no map named \"", name, "\""));
  return it->second;
}

absl::Status Store::DeleteMap(const std::string& name) {
  std::lock_guard lock(mutex_);
  auto info = catalog_->Get(name);
  if (!info.ok()) return info.status();
  if (absl::Status s = catalog_->Delete(name); !s.ok()) return s;
  if (auto it = maps_.find(name); it != maps_.end()) {
    (void)it->second->Close();
    maps_.erase(it);
  }
  std::error_code error;
  fs::remove_all(MapDir(info->id), error);
  if (error) return absl::InternalError(absl::StrCat("map deleted, but its files remain: ", error.message()));
  return absl::OkStatus();
}

absl::StatusOr<uint64_t> Store::BackupMap(const std::string& name, const std::string& dir) {
  auto map = Map(name);
  if (!map.ok()) return map.status();
  std::error_code error;
  if (fs::exists(dir, error) && !fs::is_empty(dir, error)) {
    return absl::AlreadyExistsError(absl::StrCat("backup directory ", dir, " is not empty"));
  }
  return (*map)->Backup(dir);
}

absl::StatusOr<MapInfo> Store::RestoreMap(const std::string& dir, const std::string& name) {
  std::ifstream in(dir + "/map.info", std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(dir, " holds no backup (no map.info)"));
  std::stringstream bytes;
  bytes << in.rdbuf();
  auto backed_up = DecodeMapInfo(bytes.str());
  if (!backed_up.ok()) return backed_up.status();
  MapInfo info = *backed_up;
  // Nothing is created from a damaged backup. Each shard is read in a child process, which LMDB
  // may abort on a damaged page without taking the daemon down.
  VerifyOptions verify;
  verify.isolate = true;
  if (const VerifyReport report = VerifyShards(dir, info, verify); !report.clean()) {
    return absl::DataLossError(absl::StrCat("backup ", dir, " is damaged: ", FormatProblem(report.problems[0]),
                                            report.problems.size() > 1
                                                ? absl::StrCat(" (and ", report.problems.size() - 1, " more problems)")
                                                : ""));
  }
  if (!name.empty()) info.name = name;
  std::lock_guard lock(mutex_);
  auto created = catalog_->Create(info, info.shards);
  if (!created.ok()) return created.status();
  const std::string target = MapDir(created->id);
  std::error_code error;
  fs::create_directories(target, error);
  for (uint32_t i = 0; !error && i < created->shards; ++i) {
    const std::string from = absl::StrCat(dir, "/shard-", i), to = absl::StrCat(target, "/shard-", i);
    fs::create_directories(to, error);
    if (!error) fs::copy_file(from + "/data.mdb", to + "/data.mdb", error);
  }
  if (error) {
    (void)catalog_->Delete(created->name);
    fs::remove_all(target);
    return absl::InternalError(absl::StrCat("restore from ", dir, ": ", error.message()));
  }
  if (auto map = OpenMap(*created); !map.ok()) {
    (void)catalog_->Delete(created->name);
    fs::remove_all(target);
    return map.status();
  }
  return created;
}

absl::Status Store::Close() {
  std::lock_guard lock(mutex_);
  absl::Status first;
  for (auto& [name, map] : maps_) {
    absl::Status s = map->Close();
    if (first.ok() && !s.ok()) first = s;
  }
  maps_.clear();
  return first;
}

}  // namespace fremen::storage
