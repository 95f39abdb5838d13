// The catalog of maps: name → MapInfo, in its own LMDB environment (<data dir>/catalog).
//
// Create assigns the map's id (never reused), its creation time and its default shard count; names are unique. Deleting
// a map removes only its entry: the Store removes the map's files after. A record whose checksum does not match
// (lmdb_env.h) is never taken for another map: Get answers DataLoss naming the file and key, List leaves it out of the
// page and reports it in `damaged`. Thread-safety: all methods may be called concurrently (LMDB serialises the
// writers).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/map_info.h"
#include "storage/map_page.h"

namespace fremen::storage {

// Where the files of the map with `id` live in a data directory: <data dir>/maps/<id> (store.h).
std::string MapDirIn(const std::string& data_dir, uint64_t id);


class Catalog {
 public:
  static absl::StatusOr<std::unique_ptr<Catalog>> Open(const std::string& dir);
  // An existing catalog for reading only, while no process writes it (a checker's, storage/verify.h):
  // nothing is created or written, not even a lock file.
  static absl::StatusOr<std::unique_ptr<Catalog>> OpenReadOnly(const std::string& dir);

  // InvalidArgument naming the bad field, AlreadyExists for a taken name. `default_shards` fills in info.shards when it
  // is 0. Ids for which `id_in_use` is true are skipped (the Store passes "a directory by that id exists": never hand
  // out the id of files the catalog lost track of).
  absl::StatusOr<MapInfo> Create(MapInfo info, uint32_t default_shards,
                                 const std::function<bool(uint64_t)>& id_in_use = nullptr);
  // NotFound when no map has that name.
  absl::StatusOr<MapInfo> Get(const std::string& name) const;
  // Maps in name order. page_size 0 = the default (100); at most 1000. The token is opaque.
  absl::StatusOr<MapPage> List(size_t page_size, const std::string& page_token) const;
  // NotFound when no map has that name.
  absl::Status Delete(const std::string& name);
  // Calls f(name, its info or why it does not decode) for every record in name order, damaged ones
  // included (List stops at the first). An LMDB error ends the walk and is returned.
  absl::Status ForEachRecord(const std::function<void(const std::string&, const absl::StatusOr<MapInfo>&)>& f) const;
  // Puts a map back under its own id (restore from a backup). AlreadyExists for a taken name.
  absl::Status Restore(const MapInfo& info);

 private:
  explicit Catalog(std::unique_ptr<LmdbEnv> env) : env_(std::move(env)) {}
  std::unique_ptr<LmdbEnv> env_;
};

}  // namespace fremen::storage
