// A generic map of 1024 labelled states with distinct models, and the ways to look at what a store
// kept of it, for the integrity and salvage tests: every record of a shard (to find and damage one),
// and each state's whole model as bytes (to compare what comes back).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "storage/lmdb/lmdb_env.h"
#include "storage/map_store.h"
#include "storage/model/record_codec.h"
#include "storage/shard_records.h"

namespace fremen::storage::testing {

inline constexpr uint64_t kStates = 1024;

inline MapInfo Generic(const std::string& name) {
  MapInfo info;
  info.name = name;
  info.kind = MapKind::kGeneric;
  info.shards = 1;
  return info;
}

// 1024 labelled states: every fourth never changes (a static record), the others each follow their own rhythm, so that
// no two records are alike.
inline void Fill(MapStore& map) {
  for (uint64_t i = 0; i < 24; ++i) {
    ObservationBatch b;
    b.writer_id = 1;
    b.sequence = i + 1;
    b.time = 1.7e9 + 3600.0 * i;
    for (uint64_t k = 1; k <= kStates; ++k) {
      b.keys.push_back(k);
      b.values.push_back(k % 4 == 0 ? 0.0f : static_cast<float>(std::fmod(std::sqrt(2.0) * k + 0.1 * i, 1.0)));
      if (i == 0) b.labels.push_back({k, "state" + std::to_string(k), k % 2 == 0 ? "even" : "odd"});
    }
    ASSERT_TRUE(map.Write(b).ok());
  }
}

// Each state's whole model, as bytes: equal fingerprints are equal models.
inline std::map<uint64_t, std::string> Fingerprints(const MapStore& map) {
  std::map<uint64_t, std::string> out;
  for (uint64_t k = 1; k <= kStates; ++k) {
    const auto snapshot = map.Snapshot(k);
    if (!snapshot) continue;
    std::string& f = out[k];
    f = snapshot->is_static ? "static:" + model::EncodeStaticState(snapshot->static_state)
                            : "dynamic:" + model::EncodeStateModel(*snapshot->model);
    f += "|" + snapshot->name + "|" + snapshot->group;
  }
  return out;
}

struct Record {
  std::string db;
  std::string key;
  std::string value;  // without its checksum
};

// Every record of a shard's environment, read through LmdbEnv (so checked).
inline std::vector<Record> ShardRecords(const std::string& shard_dir) {
  LmdbOptions options;
  options.databases = shard_records::AllDatabases();
  auto env = LmdbEnv::Open(shard_dir, options);
  EXPECT_TRUE(env.ok()) << env.status();
  std::vector<Record> records;
  if (!env.ok()) return records;
  EXPECT_TRUE(
      (*env)
          ->Read([&](LmdbTxn& txn) -> absl::Status {
            for (const std::string& db : options.databases) {
              const absl::Status s = txn.Scan(*txn.Db(db), {}, {}, [&](auto key, auto value) {
                records.push_back({db, std::string(key.begin(), key.end()), std::string(value.begin(), value.end())});
                return true;
              });
              if (!s.ok()) return s;
            }
            return absl::OkStatus();
          })
          .ok());
  return records;
}

inline std::span<const uint8_t> Bytes(const std::string& s) {
  return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

}  // namespace fremen::storage::testing
