// An exclusive lock on a data directory, held while the daemon runs, so that a second fremend on
// the same directory refuses to start instead of writing the same logs and shards as the first.
// flock(2) on <dir>/fremend.lock: the kernel drops it when the process dies, even by kill -9, so a
// crash never leaves a stale lock. The file holds the owner's pid, for the error message.
// Thread-compatible.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace fremen::server {

class DataDirLock {
 public:
  // FailedPrecondition naming the owner's pid when another process holds the lock.
  static absl::StatusOr<std::unique_ptr<DataDirLock>> Acquire(const std::string& dir);
  ~DataDirLock();
  DataDirLock(const DataDirLock&) = delete;
  DataDirLock& operator=(const DataDirLock&) = delete;

 private:
  explicit DataDirLock(int fd) : fd_(fd) {}
  int fd_;
};

}  // namespace fremen::server
