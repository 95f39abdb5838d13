#include "storage/catalog.h"

#include <cstring>
#include <ctime>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"

namespace fremen::storage {

namespace {

constexpr char kMapsDb[] = "maps";  // name → encoded MapInfo
constexpr char kMetaDb[] = "meta";  // "next_id" → u64
constexpr char kTokenPrefix[] = "after:";

std::span<const uint8_t> Bytes(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }
std::string_view View(std::span<const uint8_t> b) { return {reinterpret_cast<const char*>(b.data()), b.size()}; }

absl::Status PutMap(LmdbTxn& txn, const MapInfo& info) {
  auto maps = txn.Db(kMapsDb);
  if (!maps.ok()) return maps.status();
  const std::string encoded = EncodeMapInfo(info);
  const absl::Status put = txn.Put(*maps, Bytes(info.name), Bytes(encoded), MDB_NOOVERWRITE);
  if (absl::IsAlreadyExists(put)) {
    return absl::AlreadyExistsError(absl::StrCat("a map named \"", info.name, "\" already exists"));
  }
  return put;
}

}  // namespace

std::string MapDirIn(const std::string& data_dir, uint64_t id) { return absl::StrCat(data_dir, "/maps/", id); }

absl::StatusOr<std::unique_ptr<Catalog>> Catalog::Open(const std::string& dir) {
  LmdbOptions options;
  options.initial_map_size = 16ull << 20;
  options.databases = {kMapsDb, kMetaDb};
  auto env = LmdbEnv::Open(dir, options);
  if (!env.ok()) return env.status();
  return std::unique_ptr<Catalog>(new Catalog(*std::move(env)));
}

absl::StatusOr<std::unique_ptr<Catalog>> Catalog::OpenReadOnly(const std::string& dir) {
  LmdbOptions options;
  options.databases = {kMapsDb, kMetaDb};
  options.read_only = true;
  options.no_lock = true;
  auto env = LmdbEnv::Open(dir, options);
  if (!env.ok()) return env.status();
  return std::unique_ptr<Catalog>(new Catalog(*std::move(env)));
}

absl::Status Catalog::ForEachRecord(
    const std::function<void(const std::string&, const absl::StatusOr<MapInfo>&)>& f) const {
  return env_->Read([&](LmdbTxn& txn) -> absl::Status {
    auto maps = txn.Db(kMapsDb);
    if (absl::IsNotFound(maps.status())) return absl::OkStatus();
    if (!maps.ok()) return maps.status();
    return txn.ScanChecked(*maps, {}, {}, [&](auto key, auto value) {
      f(std::string(View(key)), value.ok() ? DecodeMapInfo(View(*value)) : absl::StatusOr<MapInfo>(value.status()));
      return true;
    });
  });
}

absl::StatusOr<MapInfo> Catalog::Create(MapInfo info, uint32_t default_shards,
                                        const std::function<bool(uint64_t)>& id_in_use) {
  if (info.shards == 0) info.shards = default_shards;
  if (absl::Status valid = ValidateMapInfo(info); !valid.ok()) return valid;
  info.created_unix = std::time(nullptr);
  const absl::Status written = env_->Write([&](LmdbTxn& txn) -> absl::Status {
    auto meta = txn.Db(kMetaDb);
    if (!meta.ok()) return meta.status();
    uint64_t next_id = 1;
    if (auto stored = txn.Get(*meta, Bytes("next_id")); stored.ok()) {
      if (stored->size() != 8) {
        return absl::DataLossError(absl::StrCat("catalog next_id is ", stored->size(), " bytes"));
      }
      std::memcpy(&next_id, stored->data(), 8);
    } else if (!absl::IsNotFound(stored.status())) {
      return stored.status();  // a damaged next_id must not restart ids at 1
    }
    while (id_in_use != nullptr && id_in_use(next_id)) ++next_id;
    info.id = next_id;
    ++next_id;
    uint8_t raw[8];
    std::memcpy(raw, &next_id, 8);
    if (absl::Status s = txn.Put(*meta, Bytes("next_id"), raw); !s.ok()) return s;
    return PutMap(txn, info);
  });
  if (!written.ok()) return written;
  return info;
}

absl::Status Catalog::Restore(const MapInfo& info) {
  if (absl::Status valid = ValidateMapInfo(info); !valid.ok()) return valid;
  return env_->Write([&](LmdbTxn& txn) { return PutMap(txn, info); });
}

absl::StatusOr<MapInfo> Catalog::Get(const std::string& name) const {
  absl::StatusOr<MapInfo> result = absl::NotFoundError(absl::StrCat("no map named \"", name, "\""));
  const absl::Status read = env_->Read([&](LmdbTxn& txn) -> absl::Status {
    auto maps = txn.Db(kMapsDb);
    if (absl::IsNotFound(maps.status())) return absl::OkStatus();
    if (!maps.ok()) return maps.status();
    auto value = txn.Get(*maps, Bytes(name));
    if (absl::IsNotFound(value.status())) return absl::OkStatus();
    if (!value.ok()) return value.status();
    result = DecodeMapInfo(View(*value));
    if (!result.ok()) {
      result = absl::DataLossError(absl::StrCat("catalog record \"", name, "\": ", result.status().message()));
    }
    return absl::OkStatus();
  });
  if (!read.ok()) return read;
  return result;
}

absl::StatusOr<MapPage> Catalog::List(size_t page_size, const std::string& page_token) const {
  if (page_size > kMaxPageSize) {
    return absl::InvalidArgumentError(absl::StrCat("page_size must be at most 1000, got ", page_size));
  }
  if (page_size == 0) page_size = kDefaultPageSize;
  std::string after;
  if (!page_token.empty()) {
    if (!absl::StartsWith(page_token, kTokenPrefix)) {
      return absl::InvalidArgumentError("page_token is not a token returned by a previous list");
    }
    after = page_token.substr(sizeof(kTokenPrefix) - 1);
  }
  MapPage page;
  const absl::Status read = env_->Read([&](LmdbTxn& txn) -> absl::Status {
    auto maps = txn.Db(kMapsDb);
    if (absl::IsNotFound(maps.status())) return absl::OkStatus();
    if (!maps.ok()) return maps.status();
    bool more = false;
    const absl::Status scanned = txn.ScanChecked(*maps, Bytes(after), {}, [&](auto key, auto value) {
      if (!after.empty() && View(key) == after) return true;  // the token's map was on the last page
      if (page.maps.size() == page_size) {
        more = true;
        return false;
      }
      if (!value.ok()) {
        page.damaged.push_back({std::string(View(key)), value.status()});
        return true;
      }
      auto info = DecodeMapInfo(View(*value));
      if (!info.ok()) {
        const std::string name(View(key));
        page.damaged.push_back(
            {name, absl::DataLossError(absl::StrCat("catalog record \"", name, "\": ", info.status().message()))});
        return true;
      }
      page.maps.push_back(*std::move(info));
      return true;
    });
    if (more && !page.maps.empty()) page.next_page_token = absl::StrCat(kTokenPrefix, page.maps.back().name);
    return scanned;
  });
  if (!read.ok()) return read;
  return page;
}

absl::Status Catalog::Delete(const std::string& name) {
  return env_->Write([&](LmdbTxn& txn) -> absl::Status {
    auto maps = txn.Db(kMapsDb);
    if (!maps.ok()) return maps.status();
    if (auto existing = txn.Get(*maps, Bytes(name)); !existing.ok()) {
      return absl::IsNotFound(existing.status()) ? absl::NotFoundError(absl::StrCat("no map named \"", name, "\""))
                                                 : existing.status();
    }
    return txn.Delete(*maps, Bytes(name));
  });
}

}  // namespace fremen::storage
