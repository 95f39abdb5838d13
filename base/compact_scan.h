// The encoding side of the API's compact scan (proto fremen.v1.CompactCells), for every C++ client
// (the client library, the load generator, tests): strictly increasing linear cell indices as
// LEB128 varints of their gaps, binary values as one bit per cell. The daemon's decoder is
// storage/compact_cells.h. Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace fremen {

// The varints of `indices` (REQUIRES: strictly increasing): the first index, then each gap.
inline std::string EncodeIndexGaps(std::span<const uint64_t> indices) {
  std::string out(indices.size() * 10, '\0');
  char* end = out.data();
  uint64_t previous = 0;
  for (uint64_t index : indices) {
    uint64_t v = index - previous;
    previous = index;
    while (v >= 0x80) {
      *end++ = static_cast<char>(v | 0x80);
      v >>= 7;
    }
    *end++ = static_cast<char>(v);
  }
  out.resize(static_cast<size_t>(end - out.data()));
  return out;
}

// One bit per value, cell i in bit i % 8 of byte i / 8, set for a value ≥ 0.5 (REQUIRES: values
// 0 or 1 for an exact encoding); the unused bits of the last byte are 0.
inline std::string PackOccupiedBits(std::span<const float> values) {
  std::string out((values.size() + 7) / 8, '\0');
  for (size_t i = 0; i < values.size(); ++i) {
    if (values[i] >= 0.5f) out[i / 8] = static_cast<char>(static_cast<uint8_t>(out[i / 8]) | (1u << (i % 8)));
  }
  return out;
}

// Whether every value is exactly 0 or 1, so that PackOccupiedBits loses nothing.
inline bool AllBinary(std::span<const float> values) {
  for (float v : values) {
    if (v != 0.0f && v != 1.0f) return false;
  }
  return true;
}

}  // namespace fremen
