// The YAML half of a ROS map_server / nav2 map: the metadata of an occupancy image. Only the flat
// `key: value` form that map_saver writes is read (comments, blank lines, quoted strings and a
// flow sequence for `origin`); no threads.
#pragma once

#include <string>

#include "absl/status/statusor.h"

namespace fremen::formats {

enum class MapMode {
  // Occupied, free or unknown (the default).
  kTrinary,
  // Between the thresholds, occupancy scales linearly to 0..100.
  kScale,
};

struct MapMetadata {
  // The image file as written in the YAML (relative to the YAML's directory unless absolute).
  std::string image;
  // Metres per pixel. REQUIRES: finite, > 0.
  double resolution = 0;
  // Pose of the lower-left pixel's corner: x, y (metres), yaw (radians).
  double origin_x = 0;
  double origin_y = 0;
  double origin_yaw = 0;
  // Whiter pixels are occupied (instead of blacker).
  bool negate = false;
  // map_saver's defaults. REQUIRES: 0 ≤ free_thresh < occupied_thresh ≤ 1.
  double occupied_thresh = 0.65;
  double free_thresh = 0.25;
  MapMode mode = MapMode::kTrinary;
};

// Reads and validates a map YAML. Required keys: image, resolution, origin; the others take the
// defaults above. Errors name the file, the line and the key (e.g. "map.yaml:3: resolution must be
// a number > 0, got \"abc\"").
absl::StatusOr<MapMetadata> ReadMapYaml(const std::string& path);
// The same from the text; errors name `name`.
absl::StatusOr<MapMetadata> ParseMapYaml(const std::string& text, const std::string& name);

// The path of the image: metadata.image resolved against the directory of `yaml_path`.
std::string ResolveImagePath(const std::string& yaml_path, const MapMetadata& metadata);

// Writes the YAML as map_saver does (image, mode, resolution, origin, negate, thresholds).
absl::Status WriteMapYaml(const std::string& path, const MapMetadata& metadata);

}  // namespace fremen::formats
