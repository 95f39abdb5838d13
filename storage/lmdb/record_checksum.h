// The checksum every LMDB record of fremen carries (shards and catalog alike).
//
// A stored value is the caller's value followed by a 4-byte trailer: the CRC-32 (zlib's) of the key and the value,
// little-endian. Covering the key too means a flipped bit in a key is caught as surely as one in a value (it would
// otherwise move a record to another state); a CRC catches every single-bit and every burst error up to 32 bits, the
// damage a bad disk block or a stray write leaves. LmdbTxn (lmdb_env.h) adds the trailer on Put and checks it on Get
// and Scan, so no caller sees unchecked bytes; the verifier (storage/verify.h) uses the same functions.
//
// Pure functions; thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "absl/status/statusor.h"

namespace fremen::storage {

inline constexpr size_t kRecordChecksumBytes = 4;

// The trailer of (key, value).
uint32_t RecordChecksum(std::span<const uint8_t> key, std::span<const uint8_t> value);

// Writes value and its trailer into `out` (value.size() + kRecordChecksumBytes bytes).
void EncodeChecked(std::span<const uint8_t> key, std::span<const uint8_t> value, uint8_t* out);

// The value inside a stored record; DataLoss ("checksum mismatch", or a record shorter than its trailer) when the bytes
// are not what was written. The message names neither file nor key: the caller adds them.
absl::StatusOr<std::span<const uint8_t>> CheckRecord(std::span<const uint8_t> key, std::span<const uint8_t> stored);

}  // namespace fremen::storage
