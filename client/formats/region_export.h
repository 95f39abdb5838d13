// A predicted box of a grid written as files (`fremenctl region`): a nav2/map_server PGM + YAML
// pair that the ROS navigation stack loads as the map of that time, and a PNG picture of p.
// Pure functions apart from writing the named files; thread-safe.
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "client/formats/gray_image.h"
#include "client/formats/map_yaml.h"

namespace fremen::formats {

// One plane of predicted probabilities, x fastest then y (y up, as the grid's cells).
struct ProbabilityPlane {
  uint32_t width = 0, height = 0;
  std::vector<float> p;  // width · height values in [0, 1]
  // Metric position of the plane's cell (0, 0) corner and the cell size.
  double origin_x = 0, origin_y = 0;
  double resolution = 0;
};

// The map_server image: row 0 is the plane's top row (largest y); pixels by PixelFromProbability
// with `metadata`'s mode and thresholds.
Image MapServerImage(const ProbabilityPlane& plane, const MapMetadata& metadata);

// The PNG picture: gray 255 · (1 − p), white free, black occupied, continuous in between (no
// thresholds, so that uncertain cells show as the shades they are).
Image ProbabilityImage(const ProbabilityPlane& plane);

// The metadata fremen writes: image `image_name`, the plane's resolution and origin (yaw 0),
// negate 0, ROS 1 map_saver's thresholds (0.65 / 0.196, see occupancy_pixels.h), `mode`.
MapMetadata ExportMetadata(const ProbabilityPlane& plane, const std::string& image_name, MapMode mode);

// Writes PREFIX.pgm, PREFIX.yaml (naming PREFIX.pgm by its file name, so that the pair can be
// moved together) and PREFIX.png.
absl::Status WriteRegionFiles(const std::string& prefix, const ProbabilityPlane& plane, MapMode mode);

}  // namespace fremen::formats
