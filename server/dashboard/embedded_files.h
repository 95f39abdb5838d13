// The dashboard's files (server/dashboard/web/ and Debian's Chart.js), embedded in fremend at build
// time by embed_files.cmake: the daemon serves them with no file on disk and no network access.
// Thread-safety: constant data; safe from any thread.
#pragma once

#include <string_view>

#include "absl/types/span.h"

namespace fremen::server {

struct EmbeddedFile {
  std::string_view path;          // the file's name, served at /static/<path> ("app.js")
  std::string_view content_type;  // by extension ("text/javascript; charset=utf-8")
  std::string_view bytes;
  std::string_view etag;          // the quoted SHA-256 of bytes, hex: "\"9f86d0…\""
};

// Every embedded file, in the order the build listed them (generated source).
absl::Span<const EmbeddedFile> EmbeddedFiles();

// The file of that name, or nullptr.
const EmbeddedFile* FindEmbeddedFile(std::string_view path);

}  // namespace fremen::server
