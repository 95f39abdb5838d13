#include "storage/store.h"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "absl/strings/str_cat.h"
#include "storage/catalog.h"
#include "storage/data_dir_format.h"
#include "storage/lmdb/lmdb_probe.h"
#include "storage/verify.h"

namespace fremen::storage {

namespace fs = std::filesystem;

namespace {

// The error calls on a failed map get: the open's, naming the map. Never NotFound: the catalog knows the map, its data
// is what is missing.
absl::Status Failed(const std::string& name, const absl::Status& open_error) {
  const absl::StatusCode code = absl::IsNotFound(open_error) ? absl::StatusCode::kDataLoss : open_error.code();
  return absl::Status(code, absl::StrCat("map \"", name, "\" is failed (it did not open): ", open_error.message()));
}

}  // namespace

absl::StatusOr<std::unique_ptr<Store>> Store::Open(const std::string& data_dir, const StoreOptions& options) {
  // Before anything is created or opened: a directory another version laid out is refused as it is.
  auto format = ReadDataDirFormat(options.env, data_dir);
  if (!format.ok()) return format.status();
  if (!ReadableDataDirFormat(*format)) return UnreadableFormatError(data_dir, *format);
  std::error_code error;
  fs::create_directories(data_dir + "/maps", error);
  if (error) return absl::InternalError(absl::StrCat("cannot create ", data_dir, "/maps: ", error.message()));
  if (options.probe_before_open) {
    // Without its catalog no map can be served: a damaged catalog file fails the open, but as an error naming the file
    // rather than an abort inside LMDB.
    if (absl::Status probed = ProbeEnvironments({data_dir + "/catalog"}); absl::IsDataLoss(probed)) return probed;
  }
  auto catalog = Catalog::Open(data_dir + "/catalog");
  if (!catalog.ok()) return catalog.status();
  StoreOptions resolved = options;
  if (resolved.default_shards == 0) resolved.default_shards = std::max(1u, std::thread::hardware_concurrency());
  auto store = std::unique_ptr<Store>(new Store(data_dir, resolved, *std::move(catalog)));

  std::vector<MapInfo> all;
  std::vector<DamagedCatalogEntry> damaged;
  if (absl::Status listed = store->ListCatalog(all, damaged); !listed.ok()) return listed;
  // No FORMAT: a new directory, or one format 2 wrote before it kept the file (format 1's, with
  // no record checksums, stopped at Catalog::Open: LmdbEnv refuses records without checksums).
  // Format 2 is marked 3 before a map is opened, whose next checkpoint may write a published record.
  if (*format != kDataDirFormat) {
    if (absl::Status written = WriteDataDirFormat(options.env, data_dir); !written.ok()) return written;
  }
  base::MutexLock lock(&store->mutex_);
  for (const MapInfo& info : all) {
    if (auto map = store->OpenMap(info); !map.ok()) {
      store->failed_[info.name] =
          FailedMap{info.name, info.id, store->MapDir(info.id), Failed(info.name, map.status())};
    }
  }
  for (DamagedCatalogEntry& entry : damaged) {
    store->failed_[entry.key] = FailedMap{entry.key, 0, "", Failed(entry.key, entry.status)};
  }
  store->FindUnknownDirectories(all);
  return store;
}

absl::Status Store::ListCatalog(std::vector<MapInfo>& maps, std::vector<DamagedCatalogEntry>& damaged) const {
  std::string token;
  do {
    auto page = catalog_->List(kMaxPageSize, token);
    if (!page.ok()) return page.status();
    for (MapInfo& m : page->maps) maps.push_back(std::move(m));
    for (DamagedCatalogEntry& d : page->damaged) damaged.push_back(std::move(d));
    token = page->next_page_token;
  } while (!token.empty());
  return absl::OkStatus();
}

void Store::FindUnknownDirectories(const std::vector<MapInfo>& maps) {
  std::set<std::string> known;
  for (const MapInfo& info : maps) known.insert(std::to_string(info.id));
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(data_dir_ + "/maps", error)) {
    if (!known.contains(entry.path().filename().string())) unknown_dirs_.push_back(entry.path().string());
  }
  std::sort(unknown_dirs_.begin(), unknown_dirs_.end());
}

std::vector<FailedMap> Store::FailedMaps() const {
  base::MutexLock lock(&mutex_);
  std::vector<FailedMap> failed;
  for (const auto& [name, map] : failed_) failed.push_back(map);
  std::sort(failed.begin(), failed.end(), [](const FailedMap& a, const FailedMap& b) { return a.name < b.name; });
  return failed;
}

std::vector<std::string> Store::UnknownDirectories() const { return unknown_dirs_; }

Store::Store(std::string data_dir, StoreOptions options, std::unique_ptr<Catalog> catalog)
    : data_dir_(std::move(data_dir)), options_(options), catalog_(std::move(catalog)) {}

Store::~Store() { (void)Close(); }

std::string Store::MapDir(uint64_t id) const { return MapDirIn(data_dir_, id); }

bool Store::HasDirectory(uint64_t id) const {
  std::error_code error;
  return fs::exists(MapDir(id), error) || error;  // in doubt, the id is taken
}

absl::StatusOr<std::shared_ptr<MapStore>> Store::OpenMap(const MapInfo& info) {
  const std::string dir = MapDir(info.id);
  if (options_.probe_before_open) {
    std::vector<std::string> shard_dirs;
    for (uint32_t i = 0; i < info.shards; ++i) shard_dirs.push_back(absl::StrCat(dir, "/shard-", i));
    // Unavailable (no child could be forked) tells nothing about the files: they are opened as they were before there
    // was a probe.
    if (absl::Status probed = ProbeEnvironments(shard_dirs); absl::IsDataLoss(probed)) {
      return absl::DataLossError(absl::StrCat("map ", info.name, ": ", probed.message()));
    }
  }
  auto map = MapStore::Open(info, dir, options_);
  if (!map.ok()) return map.status();
  std::shared_ptr<MapStore> shared = *std::move(map);
  maps_[info.name] = shared;
  return shared;
}

absl::StatusOr<MapInfo> Store::CreateMap(MapInfo info) {
  base::MutexLock lock(&mutex_);
  auto created =
      catalog_->Create(std::move(info), options_.default_shards, [this](uint64_t id) { return HasDirectory(id); });
  if (!created.ok()) return created.status();
  if (auto map = OpenMap(*created); !map.ok()) {
    (void)catalog_->Delete(created->name);
    std::error_code error;
    fs::remove_all(MapDir(created->id),
                   error);  // made by this call: the id had no directory
    return map.status();
  }
  return created;
}

absl::StatusOr<MapInfo> Store::GetMap(const std::string& name) const { return catalog_->Get(name); }

absl::StatusOr<MapPage> Store::ListMaps(size_t page_size, const std::string& page_token) const {
  return catalog_->List(page_size, page_token);
}

absl::StatusOr<std::shared_ptr<MapStore>> Store::Map(const std::string& name) const {
  base::MutexLock lock(&mutex_);
  if (auto it = maps_.find(name); it != maps_.end()) return it->second;
  if (auto it = failed_.find(name); it != failed_.end()) return it->second.status;
  if (salvaging_.contains(name)) {
    return absl::UnavailableError(absl::StrCat("map \"", name, "\" is being salvaged into"));
  }
  return absl::NotFoundError(absl::StrCat("no map named \"", name, "\""));
}

absl::Status Store::DeleteMap(const std::string& name) {
  base::MutexLock lock(&mutex_);
  if (salvaging_.contains(name)) {
    return absl::FailedPreconditionError(absl::StrCat("map ", name, " is being salvaged; delete it once that ends"));
  }
  auto info = catalog_->Get(name);
  if (!info.ok()) return info.status();
  if (absl::Status s = catalog_->Delete(name); !s.ok()) return s;
  if (auto it = maps_.find(name); it != maps_.end()) {
    (void)it->second->Close();
    maps_.erase(it);
  }
  failed_.erase(name);
  std::error_code error;
  fs::remove_all(MapDir(info->id), error);
  if (error) return absl::InternalError(absl::StrCat("map deleted, but its files remain: ", error.message()));
  return absl::OkStatus();
}

absl::StatusOr<uint64_t> Store::BackupMap(const std::string& name, const std::string& dir, uint64_t* lsn) {
  auto map = Map(name);
  if (!map.ok()) return map.status();
  std::error_code error;
  if (fs::exists(dir, error) && !fs::is_empty(dir, error)) {
    return absl::AlreadyExistsError(absl::StrCat("backup directory ", dir, " is not empty"));
  }
  return (*map)->Backup(dir, lsn);
}

absl::StatusOr<MapInfo> Store::RestoreMap(const std::string& dir, const std::string& name, absl::Time deadline) {
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
  verify.deadline = deadline;
  const VerifyReport report = VerifyShards(dir, info, verify);
  if (report.deadline_exceeded) {
    return absl::DeadlineExceededError(absl::StrCat("backup ", dir, " was not restored: its check did not finish by the "
                                                    "call's deadline (", FormatProblem(report.problems.back()), ")"));
  }
  if (!report.clean()) {
    return absl::DataLossError(absl::StrCat("backup ", dir, " is damaged: ", FormatProblem(report.problems[0]),
                                            report.problems.size() > 1
                                                ? absl::StrCat(" (and ", report.problems.size() - 1, " more problems)")
                                                : ""));
  }
  if (!name.empty()) info.name = name;
  base::MutexLock lock(&mutex_);
  auto created = catalog_->Create(info, info.shards, [this](uint64_t id) { return HasDirectory(id); });
  if (!created.ok()) return created.status();
  // The id has no directory (Create skipped those that do): everything under `target` is this call's, and only that is
  // removed when the restore fails.
  const std::string target = MapDir(created->id);
  std::error_code error;
  fs::create_directories(target, error);
  for (uint32_t i = 0; !error && i < created->shards; ++i) {
    const std::string from = absl::StrCat(dir, "/shard-", i), to = absl::StrCat(target, "/shard-", i);
    fs::create_directories(to, error);
    if (!error) fs::copy_file(from + "/data.mdb", to + "/data.mdb", error);
  }
  // Only a report (the last update job's record): a backup without one restores without one.
  if (!error && fs::exists(dir + "/last_update")) fs::copy_file(dir + "/last_update", target + "/last_update", error);
  const std::string incoming = absl::StrCat("/", kIncomingFile);
  if (!error && fs::exists(dir + incoming)) fs::copy_file(dir + incoming, target + incoming, error);
  if (error) {
    (void)catalog_->Delete(created->name);
    std::error_code ignored;
    fs::remove_all(target, ignored);
    return absl::InternalError(absl::StrCat("restore from ", dir, ": ", error.message()));
  }
  if (auto map = OpenMap(*created); !map.ok()) {
    (void)catalog_->Delete(created->name);
    std::error_code ignored;
    fs::remove_all(target, ignored);
    return map.status();
  }
  return created;
}

absl::Status Store::Close() {
  base::MutexLock lock(&mutex_);
  absl::Status first;
  for (auto& [name, map] : maps_) {
    absl::Status s = map->Close();
    if (first.ok() && !s.ok()) first = s;
  }
  maps_.clear();
  return first;
}

}  // namespace fremen::storage
