// Drawing on an RGB image: lines, filled rectangles and dots, clipped to the image. Enough to
// rasterise a plot without a graphics library. Thread-compatible (one image per caller).
#pragma once

#include <cstdint>

#include "client/formats/gray_image.h"

namespace fremen::formats {

struct Rgb {
  uint8_t r, g, b;
};

// Sets one pixel when (x, y) lies in the image. REQUIRES: image.channels == 3.
void PutPixel(Image& image, int x, int y, Rgb color);
// A one-pixel line from (x0, y0) to (x1, y1), both ends included (Bresenham).
void DrawLine(Image& image, int x0, int y0, int x1, int y1, Rgb color);
// Pixels x0..x1 × y0..y1, ends included.
void FillRect(Image& image, int x0, int y0, int x1, int y1, Rgb color);
// A filled disc of `radius` pixels around (x, y).
void DrawDot(Image& image, int x, int y, int radius, Rgb color);

}  // namespace fremen::formats
