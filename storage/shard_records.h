// The on-disk layout of a shard's LMDB environment (storage/shard.h): the names of its databases
// and meta records, and the decoders of the records that have no codec of their own (labels, the
// touched list, the checkpoint LSN). Shared by the shard, which writes and loads them, and by the
// verifier (storage/verify.h), which checks them without loading a shard.
// Thread-safety: pure functions and constants.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace fremen::storage::shard_records {

inline constexpr char kStaticDb[] = "static";      // brick key → StaticBrick
inline constexpr char kDynamicDb[] = "dynamic";    // state key → EncodeStateModel<float>
// state key → EncodePublishedModel: a dynamic state's published model, kept apart from its
// spectrum so that a checkpoint after the update job writes ~70 bytes a state, not ~560
// (docs/storage.md, "Published models"). A dynamic record written before data directory format 3
// holds its published model itself; a record here replaces it.
inline constexpr char kPublishedDb[] = "published";
inline constexpr char kLosslessDb[] = "lossless";  // state key → LosslessHistory
inline constexpr char kWideDb[] = "wide";          // state key → double spectrum body (WideBodies)
inline constexpr char kLabelsDb[] = "labels";      // state key → EncodeLabel
inline constexpr char kMetaDb[] = "meta";          // the keys below
inline constexpr char kLsnKey[] = "checkpoint_lsn";
inline constexpr char kDedupKey[] = "dedup";
inline constexpr char kTouchedKey[] = "touched";

// Every database of a shard, in the order the shard loads them.
inline const std::vector<std::string>& AllDatabases() {
  static const std::vector<std::string> all = {kStaticDb,   kDynamicDb, kPublishedDb, kLosslessDb,
                                                   kWideDb,     kLabelsDb,  kMetaDb};
  return all;
}

// A generic state's name and group: varint length, bytes, varint length, bytes.
std::string EncodeLabel(std::string_view name, std::string_view group);
absl::StatusOr<std::pair<std::string, std::string>> DecodeLabel(std::string_view bytes);

// The checkpoint LSN: 8 bytes in host order (as the shard has always written it).
absl::StatusOr<uint64_t> DecodeCheckpointLsn(std::span<const uint8_t> bytes);

// The touched states: a varint count, then the keys in increasing order as varint deltas.
std::string EncodeTouched(std::span<const uint64_t> sorted_keys);
absl::StatusOr<std::vector<uint64_t>> DecodeTouched(std::string_view bytes);

}  // namespace fremen::storage::shard_records
