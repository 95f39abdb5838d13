#include "server/dashboard/embedded_files.h"

namespace fremen::server {

// A linear scan: a dozen files, looked up once per request of a page that is then cached.
const EmbeddedFile* FindEmbeddedFile(std::string_view path) {
  for (const EmbeddedFile& file : EmbeddedFiles()) {
    if (file.path == path) return &file;
  }
  return nullptr;
}

}  // namespace fremen::server
