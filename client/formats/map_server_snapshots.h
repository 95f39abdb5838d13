// A directory of ROS map_server occupancy snapshots, one PGM + YAML pair per time, turned into
// grid observations (`fremenctl ingest --map-server DIR`).
//
// Which files and when: every *.yaml file of the directory is one snapshot, timed by the number
// that ends its name ("office_1700000000.yaml", "1700000000.5.yaml"); or a times file lists
// `FILE.yaml TIME` per line (names relative to the directory; '#' comments), and only those files
// are read. Cells: pixel (px, py) — row 0 the top of the image — is cell
// (offset_x + px, offset_y + height − 1 − py) of the map's grid, where the offsets place the
// snapshot's origin on the grid; unknown pixels are not observations (occupancy_pixels.h).
// No threads; functions read only the named files.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/formats/gray_image.h"
#include "client/formats/map_yaml.h"
#include "client/formats/observation_batches.h"

namespace fremen::formats {

struct SnapshotFile {
  std::string yaml_path;
  double time = 0;
};

// The snapshots of `directory` in time order. With `times_path` empty, the time comes from each
// YAML file's name (an error names a file without a trailing number and suggests --times); else
// from the times file (errors name times_path:line). A directory without snapshots is an error.
absl::StatusOr<std::vector<SnapshotFile>> ListSnapshots(const std::string& directory, const std::string& times_path);

// The time a snapshot's file name ends with: "map_1700000000.yaml" → 1700000000.
absl::StatusOr<double> TimeFromFileName(const std::string& path);

// One snapshot read: its metadata and its image.
struct Snapshot {
  MapMetadata metadata;
  Image image;
};
// Reads the YAML and the image it names; errors name the file. Refuses a rotated origin (yaw ≠ 0:
// fremen grids are axis-aligned).
absl::StatusOr<Snapshot> ReadSnapshot(const std::string& yaml_path);

// Where a grid lies, as the map holds it.
struct GridPlacement {
  double resolution = 0;
  double origin_x = 0, origin_y = 0;
  uint32_t size_x = 0, size_y = 0;
};

// The cell offsets of `snapshot` on `grid`: INVALID_ARGUMENT (naming `name`) when the resolutions
// differ, the origin is not on a cell corner of the grid, or the image does not lie inside it.
absl::Status PlaceSnapshot(const Snapshot& snapshot, const GridPlacement& grid, const std::string& name,
                           uint32_t& offset_x, uint32_t& offset_y);

// The known cells of `snapshot` at `time` as batches of at most `max_cells` observations each
// (so that each fits in one message), z = 0.
std::vector<CellBatch> SnapshotBatches(const Snapshot& snapshot, double time, uint32_t offset_x, uint32_t offset_y,
                                       size_t max_cells);

}  // namespace fremen::formats
