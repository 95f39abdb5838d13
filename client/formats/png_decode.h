// A strict PNG decoder for 8-bit grayscale and RGB, non-interlaced images (what png.h writes, and
// what most tools write for such pictures): every chunk's CRC is checked, IDAT is inflated with
// zlib and all five row filters are undone. It lets tests read back the files fremenctl writes.
// Thread-safe.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/formats/gray_image.h"

namespace fremen::formats {

// Decodes a PNG file's bytes. Errors say what is wrong (signature, chunk CRC, unsupported format,
// bad compressed data, size mismatch).
absl::StatusOr<Image> DecodePng(const std::string& bytes);
// Reads and decodes a file; errors name the path.
absl::StatusOr<Image> ReadPng(const std::string& path);

}  // namespace fremen::formats
