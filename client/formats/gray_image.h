// An 8-bit image in memory, rows top to bottom, as PGM and PNG files hold it. Plain data; no
// synchronisation (thread-compatible).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace fremen::formats {

struct Image {
  int width = 0;
  int height = 0;
  // 1 (gray) or 3 (RGB).
  int channels = 1;
  // width · height · channels bytes, row 0 first (the top of the picture), channels interleaved.
  std::vector<uint8_t> pixels;

  Image() = default;
  Image(int w, int h, int c, uint8_t fill = 0)
      : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c, fill) {}
  uint8_t& at(int x, int y, int channel = 0) {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + channel];
  }
  uint8_t at(int x, int y, int channel = 0) const {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + channel];
  }
};

}  // namespace fremen::formats
