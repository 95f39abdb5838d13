// Pixel ↔ occupancy conversion (see occupancy_pixels.h for the map_server rules followed).
#include "client/formats/occupancy_pixels.h"

#include <algorithm>
#include <cmath>

namespace fremen::formats {

double PixelOccupancy(uint8_t pixel, bool negate) {
  const double shade = pixel / 255.0;
  return negate ? shade : 1.0 - shade;
}

int CellFromPixel(uint8_t pixel, const MapMetadata& m) {
  const double occ = PixelOccupancy(pixel, m.negate);
  if (m.occupied_thresh < occ) return kCellOccupied;
  if (occ < m.free_thresh) return kCellFree;
  if (m.mode == MapMode::kTrinary) return kCellUnknown;
  return static_cast<int>(std::rint((occ - m.free_thresh) / (m.occupied_thresh - m.free_thresh) * 100.0));
}

std::optional<float> ObservationFromPixel(uint8_t pixel, const MapMetadata& m) {
  const int cell = CellFromPixel(pixel, m);
  if (cell == kCellUnknown) return std::nullopt;
  return static_cast<float>(cell) / 100.0f;
}

uint8_t PixelFromProbability(double p, const MapMetadata& m) {
  const int cell = static_cast<int>(std::rint(std::clamp(p, 0.0, 1.0) * 100.0));
  if (m.mode == MapMode::kScale) {
    return static_cast<uint8_t>(std::lround((100.0 - cell) / 100.0 * 255.0));
  }
  if (cell <= std::rint(m.free_thresh * 100.0)) return kPixelFree;
  if (cell >= std::rint(m.occupied_thresh * 100.0)) return kPixelOccupied;
  return kPixelUnknown;
}

}  // namespace fremen::formats
