// The id of a generic state known by name: a stable 64-bit hash (FNV-1a) of the name, so that any
// daemon, at any time, maps a name to the same state without a lookup table to keep consistent
// with the log. Clients that name states never see the id; clients that use ids choose their own
// (an id equal to some name's hash is the same state — 2^-64 odds by accident).
// Pure; thread-safe.
#pragma once

#include <cstdint>
#include <string_view>

namespace fremen::storage {

inline uint64_t StateIdOfName(std::string_view name) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : name) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace fremen::storage
