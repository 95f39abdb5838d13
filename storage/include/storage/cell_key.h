// State keys: the 64-bit key under which a state is stored, and the shard it lives in.
//
// Grid cells are keyed by the Morton (Z-order) code of their integer indices — 3-D (21 bits per
// axis) for a grid of several layers, 2-D for a grid one cell thick, so that a 2-D map's keys are
// dense — so that spatial neighbours are neighbours in LMDB's key order and a box is a few range
// scans. Generic states are keyed by their 64-bit id. A shard holds whole bricks — runs of 512
// consecutive keys (8×8×8 cells of a 3-D grid, 32×16 of a 2-D one) — so that a box touches few
// shards' few ranges, and in memory a brick's states sit together.
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

// The 2-D Morton code: x in the even bits, y in the odd bits.
inline uint64_t SpreadBits2(uint64_t v) {
  v &= 0xffffffffull;
  v = (v | v << 16) & 0x0000ffff0000ffffull;
  v = (v | v << 8) & 0x00ff00ff00ff00ffull;
  v = (v | v << 4) & 0x0f0f0f0f0f0f0f0full;
  v = (v | v << 2) & 0x3333333333333333ull;
  v = (v | v << 1) & 0x5555555555555555ull;
  return v;
}

inline uint64_t CompactBits2(uint64_t v) {
  v &= 0x5555555555555555ull;
  v = (v | v >> 1) & 0x3333333333333333ull;
  v = (v | v >> 2) & 0x0f0f0f0f0f0f0f0full;
  v = (v | v >> 4) & 0x00ff00ff00ff00ffull;
  v = (v | v >> 8) & 0x0000ffff0000ffffull;
  v = (v | v >> 16) & 0x00000000ffffffffull;
  return v;
}

// How the cells of one grid are keyed, and the shape of its bricks.
class GridKeys {
 public:
  // A grid with size_z == 1 is keyed in 2-D.
  static GridKeys For(uint32_t size_z) { return GridKeys(size_z == 1); }

  bool flat() const { return flat_; }
  // REQUIRES: x, y, z ≤ kMaxGridIndex (z = 0 when flat).
  uint64_t Key(uint32_t x, uint32_t y, uint32_t z) const {
    return flat_ ? SpreadBits2(x) | SpreadBits2(y) << 1 : MortonKey(x, y, z);
  }
  std::array<uint32_t, 3> Cell(uint64_t key) const {
    if (!flat_) return MortonCell(key);
    return {static_cast<uint32_t>(CompactBits2(key)), static_cast<uint32_t>(CompactBits2(key >> 1)), 0};
  }
  // Whether `key` is the key of some cell at all (the 2-D code uses 42 bits, the 3-D one 63).
  bool IsCellKey(uint64_t key) const { return key >> (flat_ ? 2 * kMortonBitsPerAxis : 3 * kMortonBitsPerAxis) == 0; }
  // Cells along x, y, z of one brick: 32×16×1 (2-D) or 8×8×8 (3-D).
  std::array<uint32_t, 3> brick_size() const {
    return flat_ ? std::array<uint32_t, 3>{32, 16, 1} : std::array<uint32_t, 3>{8, 8, 8};
  }
  // The index (0..511) of a cell within its brick: the low 9 bits of its key.
  uint32_t LocalIndex(uint32_t x, uint32_t y, uint32_t z) const {
    return static_cast<uint32_t>(Key(x & (brick_size()[0] - 1), y & (brick_size()[1] - 1), z & (brick_size()[2] - 1)));
  }

 private:
  explicit GridKeys(bool flat) : flat_(flat) {}
  bool flat_;
};

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
