// Region export (see region_export.h).
#include "client/formats/region_export.h"

#include <filesystem>

#include "base/gray_levels.h"
#include "client/formats/occupancy_pixels.h"
#include "client/formats/pgm.h"
#include "client/formats/png.h"

namespace fremen::formats {

namespace {

// Fills an image with f(p) of each cell, flipping y: image row 0 is the plane's top row.
template <typename PixelOf>
Image Render(const ProbabilityPlane& plane, PixelOf pixel_of) {
  Image image(static_cast<int>(plane.width), static_cast<int>(plane.height), 1);
  for (uint32_t y = 0; y < plane.height; ++y) {
    for (uint32_t x = 0; x < plane.width; ++x) {
      image.at(static_cast<int>(x), static_cast<int>(plane.height - 1 - y)) = pixel_of(plane.p[y * plane.width + x]);
    }
  }
  return image;
}

}  // namespace

Image MapServerImage(const ProbabilityPlane& plane, const MapMetadata& metadata) {
  return Render(plane, [&](float p) { return PixelFromProbability(p, metadata); });
}

Image ProbabilityImage(const ProbabilityPlane& plane) {
  return Render(plane, [](float p) { return GrayLevel(p); });
}

MapMetadata ExportMetadata(const ProbabilityPlane& plane, const std::string& image_name, MapMode mode) {
  MapMetadata m;
  m.image = image_name;
  m.resolution = plane.resolution;
  m.origin_x = plane.origin_x;
  m.origin_y = plane.origin_y;
  m.origin_yaw = 0;
  m.negate = false;
  m.occupied_thresh = kExportOccupiedThresh;
  m.free_thresh = kExportFreeThresh;
  m.mode = mode;
  return m;
}

absl::Status WriteRegionFiles(const std::string& prefix, const ProbabilityPlane& plane, MapMode mode) {
  const std::string pgm_path = prefix + ".pgm";
  const MapMetadata metadata = ExportMetadata(plane, std::filesystem::path(pgm_path).filename().string(), mode);
  if (absl::Status s = WritePgm(pgm_path, MapServerImage(plane, metadata)); !s.ok()) return s;
  if (absl::Status s = WriteMapYaml(prefix + ".yaml", metadata); !s.ok()) return s;
  return WritePng(prefix + ".png", ProbabilityImage(plane));
}

}  // namespace fremen::formats
