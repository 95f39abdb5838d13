// What the catalog knows about a map: its name and kind, a grid's geometry, and the model settings
// fixed at creation (docs/model.md, "Map settings").
//
// A map is either a grid (2-D when size z is 1, or 3-D) whose states are cells addressed by integer
// indices or metric points, or a set of generic states addressed by 64-bit id, with optional names
// and groups. Value types; thread-safe to share read-only.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "storage/cell_key.h"
#include "storage/model/model_settings.h"

namespace fremen::storage {

enum class MapKind : uint8_t {
  kGrid = 1,
  kGeneric = 2,
};

struct GridGeometry {
  // Edge of a cell, metres. REQUIRES: finite, > 0.
  double resolution = 0.05;
  // Metric position of the corner of cell (0, 0, 0).
  std::array<double, 3> origin = {0, 0, 0};
  // Cells along x, y, z; z = 1 for a 2-D grid. REQUIRES: each in [1, 2^21].
  std::array<uint32_t, 3> size = {1, 1, 1};

  uint64_t cell_count() const { return uint64_t{size[0]} * size[1] * size[2]; }
  bool Contains(uint32_t x, uint32_t y, uint32_t z) const { return x < size[0] && y < size[1] && z < size[2]; }
  // How this grid's cells are keyed (2-D Morton when one cell thick).
  GridKeys keys() const { return GridKeys::For(size[2]); }
  // The cell holding a metric point; nullopt outside the grid (or for a non-finite point).
  std::optional<std::array<uint32_t, 3>> CellOf(double x, double y, double z) const;
  bool operator==(const GridGeometry&) const = default;
};

// How Ω is given: harmonics of a longest period, or an explicit list.
struct PeriodSpec {
  // Longest period, seconds. Default: a week.
  double longest = model::kWeekSeconds;
  // Number of harmonics longest/k, k = 1..count. Default: 24 (a week down to 7 h).
  uint32_t count = model::kDefaultPeriodCount;
  // Round each period down to whole seconds (the original FremenServer's choice). Default: false.
  bool floor_periods = false;
  // When non-empty, Ω itself (seconds) and the three fields above are ignored.
  std::vector<double> explicit_periods;
  bool operator==(const PeriodSpec&) const = default;
};

struct MapInfo {
  // Unique, 1..128 characters of [A-Za-z0-9._-], not starting with '.'.
  std::string name;
  // Assigned by the catalog at creation; names a map's directory.
  uint64_t id = 0;
  MapKind kind = MapKind::kGrid;
  GridGeometry grid;  // kGrid only
  PeriodSpec periods;
  // L. Default 5, at most 64.
  uint32_t max_order = model::kDefaultMaxOrder;
  bool persistence = true;
  // Seconds; 0 = errors since the last update only. Default: 3 days.
  double error_half_life = model::kDefaultErrorHalfLife;
  model::ErrorCriterion criterion = model::kDefaultCriterion;
  // How the published order is chosen (docs/model.md, "Order selection"). Default: weighted, T = 0.01.
  // Maps recorded before the rule was a setting (map info version 1) read as margin 0.001, the rule
  // they were made with.
  model::OrderRule order_rule;
  // Lossless history (docs/model.md, "Lossless history") with this sampling period in seconds;
  // 0 = off. Default: off.
  double lossless_sampling_period = 0;
  // Origin of the lossless slot grid (slot 0 starts here), seconds.
  double lossless_origin = 0;
  // LMDB environments the map's states are spread over. 0 at creation = one per core.
  uint32_t shards = 0;
  // Creation time, Unix seconds.
  int64_t created_unix = 0;

  bool operator==(const MapInfo&) const = default;
};

// Checks every field; the error names the field ("grid.resolution must be ..."). Shards = 0 is
// accepted (the catalog fills it in).
absl::Status ValidateMapInfo(const MapInfo& info);

// The model settings of a valid map.
absl::StatusOr<model::ModelSettings> ModelSettingsOf(const MapInfo& info);

// Versioned binary encoding for the catalog; Decode answers DataLoss on damaged bytes.
std::string EncodeMapInfo(const MapInfo& info);
absl::StatusOr<MapInfo> DecodeMapInfo(std::string_view bytes);

}  // namespace fremen::storage
