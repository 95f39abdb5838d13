// The store: a data directory holding the catalog and every map's files, with every map open.
//
// Layout: <data dir>/catalog (LMDB), <data dir>/maps/<id>/{shard-N (LMDB), wal/}. Open() recovers every map (shards
// from their checkpoints, then their logs).
//
// Damage is reported, never repaired by deleting:
// - A map that does not open (a damaged record, a damaged LMDB file found by the probe, a log that does not replay) is
//   kept as *failed* with its reason (FailedMaps()); the other maps serve. It is still in the catalog, so GetMap and
//   ListMaps show it; Map() and every call on its data answer its error (DataLoss naming the file, or the open's own
//   error), never NotFound.
// - A damaged catalog record is a failed map named by its stored key (GetMap answers DataLoss; ListMaps leaves it out).
// - A directory under maps/ that no catalog record names (a catalog record lost to damage, or a crash between a
//   delete's catalog commit and its file removal) is left where it is and listed in UnknownDirectories() for an
//   operator; no new map is given its id. Only DeleteMap removes a map's files, and only those of the map the catalog
//   names; CreateMap, RestoreMap and SalvageMap, when they fail, remove only the directory they created.
//
// Thread-safety: every method may be called from any thread.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "storage/map_page.h"
#include "storage/map_store.h"
#include "storage/salvage.h"

namespace fremen::storage {

// A map of the catalog that is not served, and why.
struct FailedMap {
  std::string name;
  uint64_t id = 0;      // 0 when the catalog record itself is damaged
  std::string dir;      // the map's directory; empty when the id is unknown
  absl::Status status;  // what Map() answers: the open's error, naming the map (and file)
};

class Catalog;  // storage/catalog.h, private

class Store {
 public:
  // Fails only when the data directory or the catalog cannot be opened; maps that do not open are failed
  // (FailedMaps()).
  static absl::StatusOr<std::unique_ptr<Store>> Open(const std::string& data_dir, const StoreOptions& options);
  ~Store();

  absl::StatusOr<MapInfo> CreateMap(MapInfo info) ABSL_LOCKS_EXCLUDED(mutex_);
  absl::StatusOr<MapInfo> GetMap(const std::string& name) const;
  absl::StatusOr<MapPage> ListMaps(size_t page_size, const std::string& page_token) const;
  // Removes the map and all its files (a failed map too).
  absl::Status DeleteMap(const std::string& name) ABSL_LOCKS_EXCLUDED(mutex_);
  // The open map; NotFound when there is none by that name, the map's error when it is failed.
  absl::StatusOr<std::shared_ptr<MapStore>> Map(const std::string& name) const ABSL_LOCKS_EXCLUDED(mutex_);

  // A consistent copy of a map to `dir`, while it keeps serving.
  // Returns the bytes written.
  // `lsn`: as MapStore::Backup's.
  absl::StatusOr<uint64_t> BackupMap(const std::string& name, const std::string& dir, uint64_t* lsn = nullptr)
      ABSL_LOCKS_EXCLUDED(mutex_);
  // A backup made by BackupMap as a new map named `name` (empty: the backed-up map's name). The copy is probed and
  // loaded (every record checked) before the map is listed. A backup dir holding kIncomingFile (an online move's
  // snapshot, server/services/map_transfer.h) gives a map that refuses writes until its tail is applied.
  // A shard whose check has not finished by `deadline` makes it DeadlineExceeded, nothing created.
  absl::StatusOr<MapInfo> RestoreMap(const std::string& dir, const std::string& name,
                                     absl::Time deadline = absl::InfiniteFuture()) ABSL_LOCKS_EXCLUDED(mutex_);

  // A new map `new_name` (empty: name + "-salvaged") holding everything of the failed map `name` that verifies, served
  // once it opens like any other (storage/salvage.h); the failed map and its files are left as they are. NotFound for
  // an unknown map, FailedPrecondition for one that is not failed (it is copied with BackupMap/RestoreMap),
  // AlreadyExists when new_name is taken. When the copy does not open, only the directory this call made is removed.
  // The files are read and written without holding the store's lock (the other maps serve meanwhile); until the call
  // returns, both maps refuse DeleteMap and Map(new_name) answers Unavailable.
  // Not finished by `deadline`: DeadlineExceeded, and the new map's directory is removed.
  absl::StatusOr<SalvageReport> SalvageMap(const std::string& name, const std::string& new_name,
                                           absl::Time deadline = absl::InfiniteFuture()) ABSL_LOCKS_EXCLUDED(mutex_);

  // Maps that did not open at Open, in name order.
  std::vector<FailedMap> FailedMaps() const ABSL_LOCKS_EXCLUDED(mutex_);
  // Directories under <data dir>/maps that no catalog record names (full paths, sorted).
  std::vector<std::string> UnknownDirectories() const;

  // Stops every map (finishing queued writes and checkpointing).
  absl::Status Close() ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  Store(std::string data_dir, StoreOptions options, std::unique_ptr<Catalog> catalog);
  std::string MapDir(uint64_t id) const;
  // Whether maps/<id> exists: such an id is never given to a new map.
  bool HasDirectory(uint64_t id) const;
  // Probes (when enabled) and opens the map's files; on success the map is served.
  absl::StatusOr<std::shared_ptr<MapStore>> OpenMap(const MapInfo& info) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Every catalog record, good ones in `maps` and damaged ones in `damaged`.
  absl::Status ListCatalog(std::vector<MapInfo>& maps, std::vector<DamagedCatalogEntry>& damaged) const;
  void FindUnknownDirectories(const std::vector<MapInfo>& maps);

  const std::string data_dir_;
  const StoreOptions options_;
  std::unique_ptr<Catalog> catalog_;
  mutable base::Mutex mutex_;  // guards maps_, failed_, salvaging_ and serialises create/delete/restore
  absl::flat_hash_map<std::string, std::shared_ptr<MapStore>> maps_ ABSL_GUARDED_BY(mutex_);
  absl::flat_hash_map<std::string, FailedMap> failed_ ABSL_GUARDED_BY(mutex_);
  // Maps a salvage reads or creates, without holding mutex_ (SalvageMap): not deleted meanwhile.
  absl::flat_hash_set<std::string> salvaging_ ABSL_GUARDED_BY(mutex_);
  std::vector<std::string> unknown_dirs_;  // found at Open; read-only after
};

}  // namespace fremen::storage
