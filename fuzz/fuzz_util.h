// What every fuzz target shares: a check that makes libFuzzer report a crash with a message, and a
// view of the input (the maps storage's and the server's targets use are in fuzz_map.h).
// Header-only; each target is one process and single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

namespace fremen::fuzz {

// A property every input must keep (a round trip, a bound): a violation aborts, which libFuzzer
// reports as a crash and saves the input for.
#define FUZZ_CHECK(condition, what)                                                                \
  do {                                                                                             \
    if (!(condition)) {                                                                            \
      std::fprintf(stderr, "FUZZ_CHECK failed at %s:%d: %s: %s\n", __FILE__, __LINE__, #condition, \
                   std::string(what).c_str());                                                     \
      std::abort();                                                                                \
    }                                                                                              \
  } while (0)

inline std::string_view AsView(const uint8_t* data, size_t size) { return {reinterpret_cast<const char*>(data), size}; }

}  // namespace fremen::fuzz
