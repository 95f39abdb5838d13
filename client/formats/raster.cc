// Line, rectangle and dot rasterisation (see raster.h).
#include "client/formats/raster.h"

#include <algorithm>
#include <cstdlib>

namespace fremen::formats {

void PutPixel(Image& image, int x, int y, Rgb color) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
  image.at(x, y, 0) = color.r;
  image.at(x, y, 1) = color.g;
  image.at(x, y, 2) = color.b;
}

void DrawLine(Image& image, int x0, int y0, int x1, int y1, Rgb color) {
  const int dx = std::abs(x1 - x0), sx = x0 < x1 ? 1 : -1;
  const int dy = -std::abs(y1 - y0), sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  while (true) {
    PutPixel(image, x0, y0, color);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

void FillRect(Image& image, int x0, int y0, int x1, int y1, Rgb color) {
  for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y) {
    for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x) PutPixel(image, x, y, color);
  }
}

void DrawDot(Image& image, int x, int y, int radius, Rgb color) {
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (dx * dx + dy * dy <= radius * radius) PutPixel(image, x + dx, y + dy, color);
    }
  }
}

}  // namespace fremen::formats
