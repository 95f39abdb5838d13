#include "storage/env/env.h"

#include <cerrno>
#include <cstring>

#include "absl/strings/str_cat.h"

namespace fremen::storage {

absl::Status IoError(int errno_value, const std::string& what) {
  const std::string message = absl::StrCat(what, ": ", std::strerror(errno_value));
  switch (errno_value) {
    case ENOSPC:
    case EDQUOT:
      return absl::ResourceExhaustedError(message);
    case ENOENT:
      return absl::NotFoundError(message);
    case EEXIST:
      return absl::AlreadyExistsError(message);
    default:
      return absl::InternalError(message);
  }
}

std::string DirName(const std::string& path) {
  const size_t slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

absl::Status WriteFileAtomically(Env* env, const std::string& path, std::string_view bytes) {
  const std::string temporary = path + ".tmp";
  // A temporary left by a crash holds nothing anyone needs.
  if (absl::Status s = env->Unlink(temporary); !s.ok() && !absl::IsNotFound(s)) return s;
  auto file = env->NewWritableFile(temporary);
  if (!file.ok()) return file.status();
  absl::Status s = (*file)->Append({reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()});
  if (s.ok()) s = (*file)->Sync();
  if (absl::Status closed = (*file)->Close(); s.ok()) s = closed;
  if (s.ok()) s = env->Rename(temporary, path);
  if (s.ok()) s = env->SyncDir(DirName(path));
  return s;
}

}  // namespace fremen::storage
