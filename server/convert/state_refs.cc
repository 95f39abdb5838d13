#include "server/convert/state_refs.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "storage/cell_key.h"
#include "storage/state_names.h"

namespace fremen::server {

namespace {

using storage::MapInfo;
using storage::MapKind;

std::string GridSizeText(const storage::GridGeometry& grid) {
  return absl::StrCat(grid.size[0], "×", grid.size[1], "×", grid.size[2]);
}

// The name of the field a reference came from, built only for an error message: "states.cells[3]"
// (index set) or "state.cell".
struct FieldName {
  absl::string_view base;
  absl::string_view member;
  int index = -1;
  std::string str() const {
    return index < 0 ? absl::StrCat(base, ".", member) : absl::StrCat(base, ".", member, "[", index, "]");
  }
};

// FailedPrecondition unless the map is of `kind`: a request naming cells of a generic map (or ids
// of a grid) asks something of the map it does not hold.
absl::Status RequireKind(const MapInfo& map, MapKind kind, const FieldName& field) {
  if (map.kind == kind) return absl::OkStatus();
  return absl::FailedPreconditionError(
      map.kind == MapKind::kGrid
          ? absl::StrCat(field.str(), ": map ", map.name, " is a grid; name its states by cell or point")
          : absl::StrCat(field.str(), ": map ", map.name, " is a generic map; name its states by id or name"));
}

// Lengths of parallel arrays: `second` (and `third`, unless empty) must be as long as `first`.
absl::Status CheckLengths(const FieldName& list, absl::string_view first, int n_first, absl::string_view second,
                          int n_second, absl::string_view third, int n_third) {
  if (n_second == n_first && (n_third == 0 || n_third == n_first)) return absl::OkStatus();
  const std::string field = list.str();
  if (n_second != n_first) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".", second, " has ", n_second, " elements but ", field,
                                                   ".", first, " has ", n_first, "; they must be as long"));
  }
  if (n_third != 0 && n_third != n_first) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".", third, " has ", n_third, " elements but ", field, ".",
                                                   first, " has ", n_first, "; give one per element or none"));
  }
  return absl::OkStatus();
}

absl::StatusOr<uint64_t> CellKey(const MapInfo& map, uint32_t x, uint32_t y, uint32_t z, const FieldName& field) {
  if (!map.grid.Contains(x, y, z)) {
    return absl::OutOfRangeError(absl::StrCat(field.str(), " = (", x, ", ", y, ", ", z, ") is outside the grid of map ",
                                              map.name, " (", GridSizeText(map.grid), " cells)"));
  }
  return map.grid.keys().Key(x, y, z);
}

absl::StatusOr<uint64_t> PointKey(const MapInfo& map, double x, double y, double z, const FieldName& field) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    return absl::InvalidArgumentError(absl::StrCat(field.str(), " = (", x, ", ", y, ", ", z, ") must be finite"));
  }
  const std::optional<std::array<uint32_t, 3>> cell = map.grid.CellOf(x, y, z);
  if (!cell) {
    return absl::OutOfRangeError(absl::StrCat(field.str(), " = (", x, ", ", y, ", ", z,
                                              ") m is outside the grid of map ", map.name, " (",
                                              GridSizeText(map.grid), " cells of ", map.grid.resolution,
                                              " m from (", map.grid.origin[0], ", ", map.grid.origin[1], ", ",
                                              map.grid.origin[2], "))"));
  }
  return map.grid.keys().Key((*cell)[0], (*cell)[1], (*cell)[2]);
}

// The keys of cells given by index. A batched query names thousands of cells, nearly always all inside
// the grid: one branch-free pass checks them all, then the keys are made in a loop of their own
// (per-cell StatusOr and field names were a tenth of the daemon's work for a batched Predict). The
// per-cell path, which names the first cell outside, runs only for a list with one to reject.
absl::StatusOr<std::vector<uint64_t>> KeysOfCells(const MapInfo& map, const v1::CellIndices& cells,
                                                  absl::string_view field) {
  const size_t n = static_cast<size_t>(cells.x_size());
  const uint32_t* x = cells.x().data();
  const uint32_t* y = cells.y().data();
  const uint32_t* z = cells.z_size() > 0 ? cells.z().data() : nullptr;
  const std::array<uint32_t, 3>& size = map.grid.size;
  bool inside = true;
  for (size_t i = 0; i < n; ++i) inside &= (x[i] < size[0]) & (y[i] < size[1]);
  if (z) {
    for (size_t i = 0; i < n; ++i) inside &= z[i] < size[2];
  } else {
    inside &= size[2] > 0;
  }
  std::vector<uint64_t> keys(n);
  if (!inside) {
    for (size_t i = 0; i < n; ++i) {
      auto key = CellKey(map, x[i], y[i], z ? z[i] : 0, FieldName{field, "cells", static_cast<int>(i)});
      if (!key.ok()) return key.status();
    }
  }
  // GridKeys::Key's own bit spreading, in loops without its branch on the grid's kind, which the
  // compiler vectorises.
  if (map.grid.keys().flat()) {
    for (size_t i = 0; i < n; ++i) keys[i] = storage::SpreadBits2(x[i]) | storage::SpreadBits2(y[i]) << 1;
  } else if (z) {
    for (size_t i = 0; i < n; ++i) keys[i] = storage::MortonKey(x[i], y[i], z[i]);
  } else {
    for (size_t i = 0; i < n; ++i) keys[i] = storage::MortonKey(x[i], y[i], 0);
  }
  return keys;
}

absl::StatusOr<uint64_t> NameKey(const std::string& name, const FieldName& field) {
  if (name.empty()) return absl::InvalidArgumentError(absl::StrCat(field.str(), " is empty; a state's name is not"));
  return storage::StateIdOfName(name);
}

}  // namespace

uint64_t RefCount(const v1::StateRefs& refs) {
  return std::max({refs.ids_size(), refs.cells().x_size(), refs.points().x_size(), refs.names_size()});
}

absl::StatusOr<std::vector<uint64_t>> KeysOfRefs(const MapInfo& map, const v1::StateRefs& refs,
                                                 absl::string_view field) {
  const v1::CellIndices& cells = refs.cells();
  const v1::Points& points = refs.points();
  std::vector<std::string> set;
  if (refs.ids_size() > 0) set.push_back("ids");
  if (cells.x_size() + cells.y_size() + cells.z_size() > 0) set.push_back("cells");
  if (points.x_size() + points.y_size() + points.z_size() > 0) set.push_back("points");
  if (refs.names_size() > 0) set.push_back("names");
  if (set.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, " is empty; name at least one state (by ids, cells, points or names)"));
  }
  if (set.size() > 1) {
    return absl::InvalidArgumentError(absl::StrCat(field, " sets ", absl::StrJoin(set, " and "),
                                                   "; exactly one of ids, cells, points, names may be set"));
  }
  std::vector<uint64_t> keys;
  if (refs.ids_size() > 0) {
    if (absl::Status s = RequireKind(map, MapKind::kGeneric, FieldName{field, "ids"}); !s.ok()) return s;
    keys.assign(refs.ids().begin(), refs.ids().end());
  } else if (refs.names_size() > 0) {
    if (absl::Status s = RequireKind(map, MapKind::kGeneric, FieldName{field, "names"}); !s.ok()) return s;
    keys.reserve(refs.names_size());
    for (int i = 0; i < refs.names_size(); ++i) {
      auto key = NameKey(refs.names(i), FieldName{field, "names", i});
      if (!key.ok()) return key.status();
      keys.push_back(*key);
    }
  } else if (set[0] == "cells") {
    const FieldName f{field, "cells"};
    if (absl::Status s = RequireKind(map, MapKind::kGrid, f); !s.ok()) return s;
    if (absl::Status s = CheckLengths(f, "x", cells.x_size(), "y", cells.y_size(), "z", cells.z_size()); !s.ok()) {
      return s;
    }
    return KeysOfCells(map, cells, field);
  } else {
    const FieldName f{field, "points"};
    if (absl::Status s = RequireKind(map, MapKind::kGrid, f); !s.ok()) return s;
    if (absl::Status s = CheckLengths(f, "x", points.x_size(), "y", points.y_size(), "z", points.z_size());
        !s.ok()) {
      return s;
    }
    keys.reserve(points.x_size());
    for (int i = 0; i < points.x_size(); ++i) {
      auto key = PointKey(map, points.x(i), points.y(i), points.z_size() > 0 ? points.z(i) : 0.0,
                          FieldName{field, "points", i});
      if (!key.ok()) return key.status();
      keys.push_back(*key);
    }
  }
  return keys;
}

absl::StatusOr<uint64_t> KeyOfRef(const MapInfo& map, const v1::StateRef& ref, absl::string_view field) {
  switch (ref.ref_case()) {
    case v1::StateRef::kId:
      if (absl::Status s = RequireKind(map, MapKind::kGeneric, FieldName{field, "id"}); !s.ok()) return s;
      return ref.id();
    case v1::StateRef::kName:
      if (absl::Status s = RequireKind(map, MapKind::kGeneric, FieldName{field, "name"}); !s.ok()) return s;
      return NameKey(ref.name(), FieldName{field, "name"});
    case v1::StateRef::kCell: {
      const FieldName f{field, "cell"};
      if (absl::Status s = RequireKind(map, MapKind::kGrid, f); !s.ok()) return s;
      return CellKey(map, ref.cell().x(), ref.cell().y(), ref.cell().z(), f);
    }
    case v1::StateRef::kPoint: {
      const FieldName f{field, "point"};
      if (absl::Status s = RequireKind(map, MapKind::kGrid, f); !s.ok()) return s;
      return PointKey(map, ref.point().x(), ref.point().y(), ref.point().z(), f);
    }
    case v1::StateRef::REF_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError(absl::StrCat(field, " is required: set its id, cell, point or name"));
}

}  // namespace fremen::server
