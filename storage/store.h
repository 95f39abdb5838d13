// The store: a data directory holding the catalog and every map's files, with every map open.
//
// Layout: <data dir>/catalog (LMDB), <data dir>/maps/<id>/{shard-N (LMDB), wal/}. Open() recovers
// every map (shards from their checkpoints, then their logs) and removes the directories of maps
// the catalog no longer knows (a crash between a delete's catalog commit and its file removal).
// Thread-safety: every method may be called from any thread.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "storage/catalog.h"
#include "storage/map_store.h"

namespace fremen::storage {

class Store {
 public:
  static absl::StatusOr<std::unique_ptr<Store>> Open(const std::string& data_dir, const StoreOptions& options);
  ~Store();

  absl::StatusOr<MapInfo> CreateMap(MapInfo info);
  absl::StatusOr<MapInfo> GetMap(const std::string& name) const;
  absl::StatusOr<MapPage> ListMaps(size_t page_size, const std::string& page_token) const;
  // Removes the map and all its files.
  absl::Status DeleteMap(const std::string& name);
  // The open map; NotFound when there is none by that name.
  absl::StatusOr<std::shared_ptr<MapStore>> Map(const std::string& name) const;

  // A consistent copy of a map to `dir`, while it keeps serving.
  // Returns the bytes written.
  absl::StatusOr<uint64_t> BackupMap(const std::string& name, const std::string& dir);
  // A backup made by BackupMap as a new map named `name` (empty: the backed-up map's name).
  absl::StatusOr<MapInfo> RestoreMap(const std::string& dir, const std::string& name);

  // Stops every map (finishing queued writes and checkpointing).
  absl::Status Close();

 private:
  Store(std::string data_dir, StoreOptions options, std::unique_ptr<Catalog> catalog)
      : data_dir_(std::move(data_dir)), options_(options), catalog_(std::move(catalog)) {}
  std::string MapDir(uint64_t id) const;
  absl::StatusOr<std::shared_ptr<MapStore>> OpenMap(const MapInfo& info);

  const std::string data_dir_;
  const StoreOptions options_;
  std::unique_ptr<Catalog> catalog_;
  mutable std::mutex mutex_;  // guards maps_ and serialises create/delete/restore
  absl::flat_hash_map<std::string, std::shared_ptr<MapStore>> maps_;
};

}  // namespace fremen::storage
