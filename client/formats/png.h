// A minimal PNG encoder: 8-bit grayscale or RGB, no interlace, filter 0 on every row, the image
// data compressed with zlib's compress(). Enough for predicted maps and plots. Thread-safe.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/formats/gray_image.h"

namespace fremen::formats {

// The PNG file's bytes. REQUIRES: image.channels is 1 or 3, width and height ≥ 1.
absl::StatusOr<std::string> EncodePng(const Image& image);
// EncodePng, written to `path`.
absl::Status WritePng(const std::string& path, const Image& image);

}  // namespace fremen::formats
