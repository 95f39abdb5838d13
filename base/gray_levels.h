// The gray level of a value in [0, 1] in fremen's pictures of a map: 255 · (1 − v), rounded, so
// that occupied (p = 1) is black and free (p = 0) white, continuous in between. fremenctl's PNG
// files (client/formats/region_export.h) and fremend's region.png (server/gateway/region_png.h)
// draw with it, so that both show a map the same way. Pure function; thread-safe.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace fremen {

// NaN is taken as 0.5 (unknown: mid gray).
inline uint8_t GrayLevel(double v) {
  if (std::isnan(v)) v = 0.5;
  return static_cast<uint8_t>(std::lround(255.0 * (1.0 - std::clamp(v, 0.0, 1.0))));
}

}  // namespace fremen
