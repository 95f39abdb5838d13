#include "server/services/backup_path.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "absl/strings/str_cat.h"

namespace fremen::server {

namespace fs = std::filesystem;

namespace {

// "a/b/" → "a/b", so that paths compare by their components.
fs::path WithoutTrailingSlash(const fs::path& path) {
  return path.has_filename() || !path.has_parent_path() || path == path.root_path() ? path : path.parent_path();
}

}  // namespace

absl::StatusOr<std::string> ResolveBackupPath(const std::string& root, absl::string_view relative,
                                              absl::string_view field) {
  const auto invalid = [&](absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": \"", relative, "\" ", why));
  };
  if (relative.empty()) return absl::InvalidArgumentError(absl::StrCat(field, " is required"));
  if (relative.find('\0') != absl::string_view::npos) return invalid("holds a NUL character");
  const fs::path path{std::string(relative)};
  if (path.is_absolute() || relative.front() == '/') {
    return invalid("is absolute; give a directory relative to the daemon's backup_dir");
  }
  for (const fs::path& part : path) {
    if (part == "..") return invalid("holds \"..\"; give a directory inside the daemon's backup_dir");
  }
  const fs::path base = WithoutTrailingSlash(fs::path(root).lexically_normal());
  const fs::path full = WithoutTrailingSlash((base / path).lexically_normal());
  if (full == base) return invalid("names the backup root itself; give a directory inside it");
  // A link inside the root could still lead out of it.
  std::error_code error;
  const fs::path real_base = WithoutTrailingSlash(fs::weakly_canonical(base, error));
  const fs::path real_full = error ? full : WithoutTrailingSlash(fs::weakly_canonical(full, error));
  if (!error) {
    const auto [end, _] = std::mismatch(real_base.begin(), real_base.end(), real_full.begin(), real_full.end());
    if (end != real_base.end()) return invalid("leads outside the daemon's backup_dir through a symbolic link");
  }
  return full.string();
}

}  // namespace fremen::server
