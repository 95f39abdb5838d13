#include "server/convert/map_convert.h"

#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"

namespace fremen::server {

namespace {

absl::Status Invalid(absl::string_view message) { return absl::InvalidArgumentError(message); }

// Storage's messages start with its field's name; the proto's name of the same field. Longer
// prefixes first (the first match wins).
constexpr std::pair<absl::string_view, absl::string_view> kFieldNames[] = {
    {"periods: longest period", "map.periods.longest_seconds:"},
    {"periods: period count", "map.periods.count:"},
    {"periods.periods", "map.periods.explicit_seconds"},
    {"periods", "map.periods"},
    {"error_half_life", "map.error_half_life_seconds"},
    {"lossless_sampling_period", "map.lossless_sampling_seconds"},
    {"lossless_origin", "map.lossless_origin"},
    {"name", "map.name"},
    {"kind", "map.kind"},
    {"grid.", "map.grid."},
    {"max_order", "map.max_order"},
    {"criterion", "map.criterion"},
    {"order_selection", "map.order_selection"},
    {"order_margin", "map.order_margin"},
    {"order_temperature", "map.order_temperature"},
    {"shards", "map.shards"},
};

absl::StatusOr<storage::MapKind> KindFromProto(v1::MapKind kind) {
  switch (kind) {
    case v1::MAP_KIND_GRID: return storage::MapKind::kGrid;
    case v1::MAP_KIND_GENERIC: return storage::MapKind::kGeneric;
    case v1::MAP_KIND_UNSPECIFIED: return Invalid("map.kind is required: MAP_KIND_GRID or MAP_KIND_GENERIC");
    default: return Invalid(absl::StrCat("map.kind: unknown value ", static_cast<int>(kind)));
  }
}

absl::StatusOr<model::ErrorCriterion> CriterionFromProto(v1::ErrorCriterion criterion) {
  switch (criterion) {
    case v1::ERROR_CRITERION_UNSPECIFIED: return model::kDefaultCriterion;
    case v1::ERROR_CRITERION_THRESHOLD: return model::ErrorCriterion::kThreshold;
    case v1::ERROR_CRITERION_SQUARED: return model::ErrorCriterion::kSquared;
    default: return Invalid(absl::StrCat("map.criterion: unknown value ", static_cast<int>(criterion)));
  }
}

v1::ErrorCriterion CriterionToProto(model::ErrorCriterion criterion) {
  return criterion == model::ErrorCriterion::kSquared ? v1::ERROR_CRITERION_SQUARED
                                                               : v1::ERROR_CRITERION_THRESHOLD;
}

absl::StatusOr<model::OrderSelection> SelectionFromProto(v1::OrderSelection selection) {
  switch (selection) {
    case v1::ORDER_SELECTION_UNSPECIFIED: return model::OrderRule{}.selection;
    case v1::ORDER_SELECTION_MARGIN: return model::OrderSelection::kMargin;
    case v1::ORDER_SELECTION_PAPER: return model::OrderSelection::kPaper;
    case v1::ORDER_SELECTION_WEIGHTED: return model::OrderSelection::kWeighted;
    default: return Invalid(absl::StrCat("map.order_selection: unknown value ", static_cast<int>(selection)));
  }
}

v1::OrderSelection SelectionToProto(model::OrderSelection selection) {
  switch (selection) {
    case model::OrderSelection::kMargin: return v1::ORDER_SELECTION_MARGIN;
    case model::OrderSelection::kPaper: return v1::ORDER_SELECTION_PAPER;
    case model::OrderSelection::kWeighted: return v1::ORDER_SELECTION_WEIGHTED;
  }
  return v1::ORDER_SELECTION_UNSPECIFIED;
}

void GridFromProto(const v1::GridGeometry& grid, storage::GridGeometry& out) {
  out.resolution = grid.resolution();
  out.origin = {grid.origin().x(), grid.origin().y(), grid.origin().z()};
  // An unset z is a 2-D grid: one layer.
  out.size = {grid.size().x(), grid.size().y(), grid.size().z() == 0 ? 1u : grid.size().z()};
}

void PeriodsFromProto(const v1::PeriodSpec& periods, storage::PeriodSpec& out) {
  if (periods.has_longest_seconds()) out.longest = periods.longest_seconds();
  if (periods.has_count()) out.count = periods.count();
  out.floor_periods = periods.floor_periods();
  out.explicit_periods.assign(periods.explicit_seconds().begin(), periods.explicit_seconds().end());
}

}  // namespace

absl::Status RenameStorageFields(const absl::Status& status) {
  if (status.code() != absl::StatusCode::kInvalidArgument) return status;
  const absl::string_view message = status.message();
  for (const auto& [storage_name, proto_name] : kFieldNames) {
    if (absl::StartsWith(message, storage_name)) {
      return Invalid(absl::StrCat(proto_name, message.substr(storage_name.size())));
    }
  }
  return Invalid(absl::StrCat("map: ", message));
}

absl::StatusOr<storage::MapInfo> MapInfoFromProto(const v1::Map& map) {
  storage::MapInfo info;
  info.name = map.name();
  auto kind = KindFromProto(map.kind());
  if (!kind.ok()) return kind.status();
  info.kind = *kind;
  if (info.kind == storage::MapKind::kGrid) {
    if (!map.has_grid()) return Invalid("map.grid is required for a MAP_KIND_GRID map");
    GridFromProto(map.grid(), info.grid);
  } else if (map.has_grid()) {
    return Invalid("map.grid must be unset for a MAP_KIND_GENERIC map");
  }
  PeriodsFromProto(map.periods(), info.periods);
  if (map.has_max_order()) info.max_order = map.max_order();
  if (map.has_persistence()) info.persistence = map.persistence();
  if (map.has_error_half_life_seconds()) info.error_half_life = map.error_half_life_seconds();
  auto criterion = CriterionFromProto(map.criterion());
  if (!criterion.ok()) return criterion.status();
  info.criterion = *criterion;
  auto selection = SelectionFromProto(map.order_selection());
  if (!selection.ok()) return selection.status();
  info.order_rule.selection = *selection;
  if (map.has_order_margin()) info.order_rule.margin = map.order_margin();
  if (map.has_order_temperature()) info.order_rule.temperature = map.order_temperature();
  info.lossless_sampling_period = map.lossless_sampling_seconds();
  info.lossless_origin = map.lossless_origin();
  info.shards = map.shards();
  if (absl::Status valid = storage::ValidateMapInfo(info); !valid.ok()) return RenameStorageFields(valid);
  return info;
}

void MapInfoToProto(const storage::MapInfo& info, v1::Map& out) {
  out.Clear();
  out.set_name(info.name);
  out.set_kind(info.kind == storage::MapKind::kGrid ? v1::MAP_KIND_GRID : v1::MAP_KIND_GENERIC);
  if (info.kind == storage::MapKind::kGrid) {
    v1::GridGeometry& grid = *out.mutable_grid();
    grid.set_resolution(info.grid.resolution);
    grid.mutable_origin()->set_x(info.grid.origin[0]);
    grid.mutable_origin()->set_y(info.grid.origin[1]);
    grid.mutable_origin()->set_z(info.grid.origin[2]);
    grid.mutable_size()->set_x(info.grid.size[0]);
    grid.mutable_size()->set_y(info.grid.size[1]);
    grid.mutable_size()->set_z(info.grid.size[2]);
  }
  v1::PeriodSpec& periods = *out.mutable_periods();
  periods.set_longest_seconds(info.periods.longest);
  periods.set_count(info.periods.count);
  periods.set_floor_periods(info.periods.floor_periods);
  periods.mutable_explicit_seconds()->Add(info.periods.explicit_periods.begin(), info.periods.explicit_periods.end());
  out.set_max_order(info.max_order);
  out.set_persistence(info.persistence);
  out.set_error_half_life_seconds(info.error_half_life);
  out.set_criterion(CriterionToProto(info.criterion));
  out.set_order_selection(SelectionToProto(info.order_rule.selection));
  out.set_order_margin(info.order_rule.margin);
  out.set_order_temperature(info.order_rule.temperature);
  out.set_lossless_sampling_seconds(info.lossless_sampling_period);
  out.set_lossless_origin(info.lossless_origin);
  out.set_shards(info.shards);
  out.mutable_create_time()->set_seconds(info.created_unix);
}

v1::MapMoveState MoveStateToProto(storage::MoveState state) {
  switch (state) {
    case storage::MoveState::kServing:
      return v1::MAP_MOVE_STATE_SERVING;
    case storage::MoveState::kWritesStopped:
      return v1::MAP_MOVE_STATE_WRITES_STOPPED;
    case storage::MoveState::kMoved:
      return v1::MAP_MOVE_STATE_MOVED;
    case storage::MoveState::kCopying:
      return v1::MAP_MOVE_STATE_COPYING;
    case storage::MoveState::kIncoming:
      return v1::MAP_MOVE_STATE_INCOMING;
  }
  return v1::MAP_MOVE_STATE_UNSPECIFIED;
}

void AddMoveState(const storage::Store& store, v1::Map& map) {
  auto open = store.Map(map.name());
  if (!open.ok()) return;
  const storage::MoveStatus move = (*open)->Move();
  map.set_move_state(MoveStateToProto(move.state));
  map.set_moved_to(move.moved_to);
}

}  // namespace fremen::server
