// PGM (Netpbm gray map) files, the image half of a ROS map_server map: read P5 (binary) and P2
// (ASCII), write P5. No threads; functions touch only the named file.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/formats/gray_image.h"

namespace fremen::formats {

// Reads a P5 or P2 file into a 1-channel image. A maxval other than 255 (1..65535) is rescaled to
// 0..255, as image loaders used by map_server do. Errors name the path and what is wrong (magic,
// header field, truncated data).
absl::StatusOr<Image> ReadPgm(const std::string& path);
// The same from the file's bytes; errors name `name`.
absl::StatusOr<Image> ParsePgm(const std::string& bytes, const std::string& name);

// Writes a 1-channel image as P5 with maxval 255. REQUIRES: image.channels == 1.
absl::Status WritePgm(const std::string& path, const Image& image);

}  // namespace fremen::formats
