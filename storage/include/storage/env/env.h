// The file system as a map store sees it, after LevelDB's Env: the write-ahead log's segments and
// the small files the store writes itself (<map dir>/last_update, a backup's map.info) go through
// an Env, so that tests can swap in one that loses unsynced bytes, fails fsync or fills the disk
// (fault_injection_env.h). LMDB does its own I/O and stays outside.
//
// Errors: ENOSPC (and EDQUOT) give ResourceExhausted, ENOENT NotFound, EEXIST AlreadyExists, any
// other errno Internal; the message names the operation, the path and strerror. Thread-safety: an
// Env may be used from any thread; one WritableFile by one thread at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fremen::storage {

// A file open for appending.
class WritableFile {
 public:
  virtual ~WritableFile() = default;
  // Appends at the end of the file. After an error an unknown prefix of `data` may be in the file.
  virtual absl::Status Append(std::span<const uint8_t> data) = 0;
  // Makes every byte appended so far durable (fdatasync; the size too).
  virtual absl::Status Sync() = 0;
  // Closes without syncing. Idempotent; the destructor closes too.
  virtual absl::Status Close() = 0;
};

class Env {
 public:
  virtual ~Env() = default;
  // The POSIX file system; process-wide, never deleted.
  static Env* Default();

  // Creates an empty file; AlreadyExists when there is one, so that nothing is overwritten by
  // accident (replace a file with WriteFileAtomically). Its directory entry is durable only after
  // SyncDir of its directory.
  virtual absl::StatusOr<std::unique_ptr<WritableFile>> NewWritableFile(const std::string& path) = 0;
  // Opens an existing file to append at its end; NotFound when there is none.
  virtual absl::StatusOr<std::unique_ptr<WritableFile>> NewAppendableFile(const std::string& path) = 0;
  // The whole file; NotFound when it does not exist.
  virtual absl::StatusOr<std::string> ReadFile(const std::string& path) = 0;
  virtual absl::StatusOr<uint64_t> FileSize(const std::string& path) = 0;
  // The names in `dir`, without "." and "..", in no order; NotFound when it does not exist.
  virtual absl::StatusOr<std::vector<std::string>> ListDir(const std::string& dir) = 0;
  // Creates a directory; OK when it exists already.
  virtual absl::Status CreateDir(const std::string& dir) = 0;
  // Cuts a file to `size` bytes and makes the new size durable.
  virtual absl::Status Truncate(const std::string& path, uint64_t size) = 0;
  virtual absl::Status Unlink(const std::string& path) = 0;
  // Replaces `to` atomically. Durable only after SyncDir of the directory.
  virtual absl::Status Rename(const std::string& from, const std::string& to) = 0;
  // Makes the directory's entries (creations, renames, unlinks in it) durable.
  virtual absl::Status SyncDir(const std::string& dir) = 0;
};

// The status of a failed system call: `what` (e.g. "fdatasync /a/b") and strerror(errno_value),
// with the code the header promises. Shared by every Env so that faults look like real ones.
absl::Status IoError(int errno_value, const std::string& what);

// Replaces `path` with `bytes` atomically and durably: a temporary file beside it, synced, renamed
// over it, and the directory synced. A crash leaves the old or the new content.
absl::Status WriteFileAtomically(Env* env, const std::string& path, std::string_view bytes);

// The directory part of a path ("." when it has none).
std::string DirName(const std::string& path);

}  // namespace fremen::storage
