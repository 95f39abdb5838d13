// State keys: the 64-bit key under which a state is stored, and the shard it lives in.
//
// Grid cells are keyed by the Morton (Z-order) code of their integer indices, 21 bits per axis,
// so that spatial neighbours are neighbours in LMDB's key order and a box is a few range scans
// (SPEC §1). Generic states are keyed by their 64-bit id. A shard holds whole bricks — runs of 512
// consecutive keys (an 8×8×8 block of a 3-D grid) — so that a box touches few shards' few ranges.
// Pure functions; thread-safe.
#pragma once

#include <array>
#include <cstdint>

namespace fremen::storage {

inline constexpr int kMortonBitsPerAxis = 21;
inline constexpr uint32_t kMaxGridIndex = (1u << kMortonBitsPerAxis) - 1;
inline constexpr int kBrickBits = 9;  // 512 keys per brick

// Spreads the low 21 bits of v so that two zero bits separate each.
inline uint64_t SpreadBits3(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

inline uint64_t CompactBits3(uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ull;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00full;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffull;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffull;
  v = (v ^ (v >> 32)) & 0x1fffff;
  return v;
}

// REQUIRES: x, y, z ≤ kMaxGridIndex.
inline uint64_t MortonKey(uint32_t x, uint32_t y, uint32_t z) {
  return SpreadBits3(x) | SpreadBits3(y) << 1 | SpreadBits3(z) << 2;
}

inline std::array<uint32_t, 3> MortonCell(uint64_t key) {
  return {static_cast<uint32_t>(CompactBits3(key)), static_cast<uint32_t>(CompactBits3(key >> 1)),
          static_cast<uint32_t>(CompactBits3(key >> 2))};
}

inline uint64_t BrickOf(uint64_t key) { return key >> kBrickBits; }

// The shard of a key: bricks are spread over shards by a hash, so that neighbouring bricks (and
// so a robot's scan) load all shards evenly.
inline uint32_t ShardOf(uint64_t key, uint32_t shard_count) {
  uint64_t h = BrickOf(key) * 0x9E3779B97F4A7C15ull;
  h ^= h >> 29;
  return static_cast<uint32_t>(h % shard_count);
}

// Big-endian bytes of a key, so that LMDB's byte order is the key order.
inline std::array<uint8_t, 8> KeyBytes(uint64_t key) {
  std::array<uint8_t, 8> out;
  for (int i = 0; i < 8; ++i) out[i] = static_cast<uint8_t>(key >> (56 - 8 * i));
  return out;
}

inline uint64_t KeyFromBytes(const uint8_t* bytes) {
  uint64_t key = 0;
  for (int i = 0; i < 8; ++i) key = key << 8 | bytes[i];
  return key;
}

}  // namespace fremen::storage
