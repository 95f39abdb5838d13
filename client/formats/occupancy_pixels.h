// Conversion between map_server image pixels and occupancy, exactly as ROS map_server / nav2 do it,
// so that fremen reads and writes maps that the ROS navigation stack reads back the same way.
//
// Reference: nav2_map_server/src/map_io.cpp (ros-navigation/navigation2), loadMapFromFile and
// tryWriteMapToFile:
// - reading: shade = v / 255, occ = negate ? shade : 1 − shade (so p = (255 − v) / 255 unless
//   negate). Trinary: occ > occupied_thresh → occupied (100), occ < free_thresh → free (0),
//   otherwise unknown (−1). Scale: the same thresholds, and in between
//   rint((occ − free_thresh) / (occupied_thresh − free_thresh) · 100).
// - writing trinary: cell = occupancy in percent; cell ≤ rint(100 · free_thresh) → 254,
//   cell ≥ rint(100 · occupied_thresh) → 0, otherwise (and unknown) → 205. Scale: gray
//   (100 − cell) / 100.
// - image row 0 is the top of the map: cell (x, y) of the grid is pixel (x, height − 1 − y).
// Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <optional>

#include "client/formats/map_yaml.h"

namespace fremen::formats {

// The occupancy of a cell as map_server's OccupancyGrid holds it.
inline constexpr int kCellUnknown = -1;
inline constexpr int kCellFree = 0;
inline constexpr int kCellOccupied = 100;

// The pixel values map_saver writes in trinary mode.
inline constexpr uint8_t kPixelFree = 254;
inline constexpr uint8_t kPixelOccupied = 0;
inline constexpr uint8_t kPixelUnknown = 205;

// The thresholds fremen writes into exported YAML files: ROS 1 map_saver's. (With nav2's free
// threshold 0.25 an unknown pixel, 205, would read back as free: occ = 50/255 ≈ 0.196 < 0.25.)
inline constexpr double kExportOccupiedThresh = 0.65;
inline constexpr double kExportFreeThresh = 0.196;

// occ of a pixel, before thresholding: (255 − v) / 255, or v / 255 when negate.
double PixelOccupancy(uint8_t pixel, bool negate);

// The OccupancyGrid cell map_server loads from `pixel`: kCellUnknown, or 0..100.
int CellFromPixel(uint8_t pixel, const MapMetadata& metadata);

// The observation fremen ingests for `pixel`: 0 free, 1 occupied, cell / 100 in scale mode's
// in-between band; nullopt for an unknown cell (nothing was observed there).
std::optional<float> ObservationFromPixel(uint8_t pixel, const MapMetadata& metadata);

// The pixel map_saver writes for occupancy probability `p` in [0, 1] (clamped), with the
// thresholds and mode of `metadata` (negate is ignored, as map_saver always writes negate 0).
uint8_t PixelFromProbability(double p, const MapMetadata& metadata);

}  // namespace fremen::formats
