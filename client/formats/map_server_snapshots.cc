// Snapshot directories of map_server maps (see map_server_snapshots.h).
#include "client/formats/map_server_snapshots.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "client/formats/occupancy_pixels.h"
#include "client/formats/pgm.h"

namespace fremen::formats {

namespace fs = std::filesystem;

namespace {

bool ParseTime(std::string_view text, double& value) {
  if (text.empty()) return false;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && ptr == text.data() + text.size() && std::isfinite(value) && std::fabs(value) <= 1e13;
}

absl::StatusOr<std::vector<SnapshotFile>> ReadTimesFile(const std::string& directory, const std::string& times_path) {
  std::ifstream in(times_path);
  if (!in) return absl::NotFoundError(absl::StrCat(times_path, ": cannot open: ", std::strerror(errno)));
  std::vector<SnapshotFile> files;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream fields(line);
    std::string name, time_text, extra;
    if (!(fields >> name) || name.front() == '#') continue;
    double time;
    if (!(fields >> time_text) || (fields >> extra)) {
      return absl::InvalidArgumentError(
          absl::StrCat(times_path, ":", number, ": expected `FILE.yaml TIME`, got \"", line, "\""));
    }
    if (!ParseTime(time_text, time)) {
      return absl::InvalidArgumentError(absl::StrCat(
          times_path, ":", number, ": TIME must be a finite number of seconds within ±1e13, got \"", time_text, "\""));
    }
    const fs::path path = fs::path(name).is_absolute() ? fs::path(name) : fs::path(directory) / name;
    if (!fs::is_regular_file(path)) {
      return absl::NotFoundError(absl::StrCat(times_path, ":", number, ": no file ", path.string()));
    }
    files.push_back({path.string(), time});
  }
  if (in.bad()) return absl::DataLossError(absl::StrCat(times_path, ": read error"));
  return files;
}

}  // namespace

absl::StatusOr<double> TimeFromFileName(const std::string& path) {
  const std::string stem = fs::path(path).stem().string();
  // The longest tail of digits, with at most one '.', and an optional '-' only at the start of
  // the name (elsewhere '-' separates words: "office-1700000000").
  size_t begin = stem.size();
  bool dot = false;
  while (begin > 0) {
    const char c = stem[begin - 1];
    if (std::isdigit(static_cast<unsigned char>(c))) {
      --begin;
    } else if (c == '.' && !dot && begin < stem.size()) {
      dot = true;
      --begin;
    } else {
      break;
    }
  }
  if (begin < stem.size() && stem[begin] == '.') ++begin;  // "map.5" is not the time .5
  if (begin == 1 && stem[0] == '-') begin = 0;
  double time;
  if (begin == stem.size() || !ParseTime(std::string_view(stem).substr(begin), time)) {
    return absl::InvalidArgumentError(
        absl::StrCat(path,
                     ": the file name does not end with its time in seconds (e.g. office_1700000000.yaml); rename the "
                     "files or list `FILE.yaml TIME` lines in a --times file"));
  }
  return time;
}

absl::StatusOr<std::vector<SnapshotFile>> ListSnapshots(const std::string& directory, const std::string& times_path) {
  std::error_code error;
  if (!fs::is_directory(directory, error)) {
    return absl::NotFoundError(absl::StrCat(directory, ": not a directory of map_server snapshots"));
  }
  std::vector<SnapshotFile> files;
  if (!times_path.empty()) {
    absl::StatusOr<std::vector<SnapshotFile>> listed = ReadTimesFile(directory, times_path);
    if (!listed.ok()) return listed.status();
    files = *std::move(listed);
  } else {
    std::vector<std::string> paths;
    for (const fs::directory_entry& entry : fs::directory_iterator(directory, error)) {
      const std::string extension = entry.path().extension().string();
      if (entry.is_regular_file() && (extension == ".yaml" || extension == ".yml"))
        paths.push_back(entry.path().string());
    }
    if (error) return absl::NotFoundError(absl::StrCat(directory, ": cannot list: ", error.message()));
    std::sort(paths.begin(), paths.end());
    for (const std::string& path : paths) {
      absl::StatusOr<double> time = TimeFromFileName(path);
      if (!time.ok()) return time.status();
      files.push_back({path, *time});
    }
  }
  if (files.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(times_path.empty() ? directory : times_path, ": no map_server snapshots (*.yaml) to import"));
  }
  std::stable_sort(files.begin(), files.end(),
                   [](const SnapshotFile& a, const SnapshotFile& b) { return a.time < b.time; });
  return files;
}

absl::StatusOr<Snapshot> ReadSnapshot(const std::string& yaml_path) {
  absl::StatusOr<MapMetadata> metadata = ReadMapYaml(yaml_path);
  if (!metadata.ok()) return metadata.status();
  if (metadata->origin_yaw != 0) {
    return absl::InvalidArgumentError(absl::StrCat(yaml_path, ": origin yaw must be 0, got ", metadata->origin_yaw,
                                                   " (fremen grids are axis-aligned; rotate the map first)"));
  }
  absl::StatusOr<Image> image = ReadPgm(ResolveImagePath(yaml_path, *metadata));
  if (!image.ok()) return image.status();
  return Snapshot{*std::move(metadata), *std::move(image)};
}

absl::Status PlaceSnapshot(const Snapshot& snapshot, const GridPlacement& grid, const std::string& name,
                           uint32_t& offset_x, uint32_t& offset_y) {
  const MapMetadata& m = snapshot.metadata;
  if (std::fabs(m.resolution - grid.resolution) > 1e-9 * grid.resolution) {
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": resolution ", m.resolution, " differs from the map's grid resolution ", grid.resolution));
  }
  // Cell offsets of the snapshot's corner; it must sit on a cell corner (within a thousandth of a
  // cell, the precision of a YAML written with a few decimals).
  const double fx = (m.origin_x - grid.origin_x) / grid.resolution;
  const double fy = (m.origin_y - grid.origin_y) / grid.resolution;
  const double rx = std::round(fx), ry = std::round(fy);
  if (std::fabs(fx - rx) > 1e-3 || std::fabs(fy - ry) > 1e-3) {
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": origin (", m.origin_x, ", ", m.origin_y, ") is not on a cell corner of the map's grid (origin (",
        grid.origin_x, ", ", grid.origin_y, "), resolution ", grid.resolution, ")"));
  }
  if (rx < 0 || ry < 0 || rx + snapshot.image.width > grid.size_x || ry + snapshot.image.height > grid.size_y) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": the ", snapshot.image.width, "x", snapshot.image.height,
                                                   " image at cell (", rx, ", ", ry, ") does not lie inside the map's ",
                                                   grid.size_x, "x", grid.size_y, " grid"));
  }
  offset_x = static_cast<uint32_t>(rx);
  offset_y = static_cast<uint32_t>(ry);
  return absl::OkStatus();
}

std::vector<CellBatch> SnapshotBatches(const Snapshot& snapshot, double time, uint32_t offset_x, uint32_t offset_y,
                                       size_t max_cells) {
  std::vector<CellBatch> batches;
  const Image& image = snapshot.image;
  for (int py = 0; py < image.height; ++py) {
    for (int px = 0; px < image.width; ++px) {
      const std::optional<float> value = ObservationFromPixel(image.at(px, py), snapshot.metadata);
      if (!value) continue;
      if (batches.empty() || batches.back().size() >= max_cells) {
        batches.emplace_back();
        batches.back().time = time;
      }
      batches.back().Add(offset_x + px, offset_y + (image.height - 1 - py), 0, *value);
    }
  }
  return batches;
}

}  // namespace fremen::formats
