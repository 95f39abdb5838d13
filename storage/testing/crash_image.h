// What `kill -9` leaves of a running store, for in-process tests: its files copied as they are now
// (a killed process loses nothing the kernel has: every written byte is in the page cache), without
// LMDB's lock files, which belong to the running process. REQUIRES: no checkpoint is being written.
#pragma once

#include <filesystem>
#include <string>

namespace fremen::storage::testing {

inline void CopyCrashImage(const std::string& from, const std::string& to) {
  namespace fs = std::filesystem;
  fs::create_directories(to);
  for (const auto& entry : fs::recursive_directory_iterator(from)) {
    const fs::path target = fs::path(to) / fs::relative(entry.path(), from);
    if (entry.is_directory()) {
      fs::create_directories(target);
    } else if (entry.path().filename() != "lock.mdb") {
      fs::copy_file(entry.path(), target, fs::copy_options::overwrite_existing);
    }
  }
}

}  // namespace fremen::storage::testing
