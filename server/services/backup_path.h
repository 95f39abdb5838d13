// Where BackupMap writes and RestoreMap reads: a directory named by the client relative to the
// daemon's backup root (config backup_dir). The client never names an arbitrary path of the
// daemon's machine: absolute paths, ".." and a path that leaves the root through a symbolic link
// are refused.
// Pure functions (apart from resolving the symbolic links already on disk); thread-safe.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace fremen::server {

// root/relative, normalised. InvalidArgument naming `field` when `relative` is empty, absolute,
// holds a ".." component or a NUL, or resolves (through links) outside `root`.
// REQUIRES: `root` is absolute.
absl::StatusOr<std::string> ResolveBackupPath(const std::string& root, absl::string_view relative,
                                              absl::string_view field);

}  // namespace fremen::server
