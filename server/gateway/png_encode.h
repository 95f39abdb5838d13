// 8-bit grayscale PNG files, encoded by libpng (Debian's libpng-dev), in memory: what
// GET /v1/maps/{map}/region.png answers. Pure function; thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "absl/status/statusor.h"

namespace fremen::server {

// The PNG file of a width × height gray image, `pixels` row 0 (the top) first.
// InvalidArgument when the sizes are zero or do not match `pixels`.
absl::StatusOr<std::string> EncodeGrayPng(uint32_t width, uint32_t height, std::span<const uint8_t> pixels);

}  // namespace fremen::server
