// The layout version of a data directory, kept in <data dir>/FORMAT ("fremen data directory format
// 3"), so that a fremend refuses, with a message that says so, a directory that another version laid
// out differently, instead of reading its every record as damage (docs/storage.md, "Data directory
// format").
//
// Format 3 keeps a dynamic state's published model in a database of its own (shard_records.h,
// kPublishedDb): a fremend of format 2 would not read it and would serve stale models. Format 2 is
// the first with a checksum in every LMDB record; its directories are read as they are (a dynamic
// record holding its published model is still read) and marked format 3 before any map is opened,
// so that an older fremend refuses them from then on. Format 1 (no record checksums, no
// FORMAT file) cannot be read by this version: its catalog is refused when it is opened
// (LmdbEnv's record format check, lmdb/lmdb_env.h). A directory without the file whose catalog
// opens was written by format 2 before it kept the file, and is marked.
// Thread-safety: pure functions over the file system.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "storage/env/env.h"

namespace fremen::storage {

inline constexpr int kDataDirFormat = 3;
// The oldest format this version reads (and marks kDataDirFormat when it opens the directory).
inline constexpr int kOldestReadableDataDirFormat = 2;

// Whether this version reads a directory of `format` (0: no FORMAT file, see above).
inline bool ReadableDataDirFormat(int format) {
  return format == 0 || (format >= kOldestReadableDataDirFormat && format <= kDataDirFormat);
}

// The directory's format: the number in its FORMAT file, 0 when it has none.
// DataLoss naming the file when the file says something else than "fremen data directory format N".
absl::StatusOr<int> ReadDataDirFormat(Env* env, const std::string& data_dir);

// Writes FORMAT with kDataDirFormat, atomically and durably.
absl::Status WriteDataDirFormat(Env* env, const std::string& data_dir);

// FailedPrecondition for a format this version does not read, naming both and what to do.
absl::Status UnreadableFormatError(const std::string& data_dir, int format);

}  // namespace fremen::storage
