#include "client/lib/scan_builder.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "base/compact_scan.h"

namespace fremen::client {

namespace {

constexpr double kMaxAbsTime = 1e13;

void SetPatchShape(Cell origin, GridShape shape, v1::DensePatch& patch) {
  patch.mutable_origin()->set_x(origin.x);
  patch.mutable_origin()->set_y(origin.y);
  patch.mutable_origin()->set_z(origin.z);
  patch.mutable_size()->set_x(shape.x);
  patch.mutable_size()->set_y(shape.y);
  patch.mutable_size()->set_z(shape.z);
}

const char* KindName(int kind) {
  static const char* const kNames[] = {"nothing", "cells", "points", "a patch", "states by id", "states by name"};
  return kNames[kind];
}

}  // namespace

ScanBuilder::ScanBuilder(double time) { request_.set_time(time); }

bool ScanBuilder::Use(Kind kind, const char* what) {
  if (!error_.ok()) return false;
  if (kind_ == Kind::kNone) {
    kind_ = kind;
    return true;
  }
  if (kind_ == kind && kind != Kind::kPatch) return true;
  error_ = absl::InvalidArgumentError(kind == Kind::kPatch && kind_ == Kind::kPatch
                                          ? std::string("a scan holds one patch: build one scan per patch")
                                          : absl::StrCat("a scan holds one kind of observations: this one has ",
                                                         KindName(static_cast<int>(kind_)), ", so ", what,
                                                         " needs a scan of its own"));
  return false;
}

ScanBuilder& ScanBuilder::AddCell(Cell cell, float value) {
  if (!Use(Kind::kCells, "AddCell")) return *this;
  v1::CellObservations* cells = request_.mutable_cells();
  cells->mutable_cells()->add_x(cell.x);
  cells->mutable_cells()->add_y(cell.y);
  cells->mutable_cells()->add_z(cell.z);
  cells->add_values(value);
  ++observations_;
  return *this;
}

ScanBuilder& ScanBuilder::SetGrid(GridShape grid) {
  grid_ = grid;
  return *this;
}

void ScanBuilder::MaybeCompact() {
  if (grid_.x == 0 || kind_ != Kind::kCells) return;
  const v1::CellObservations& cells = request_.cells();
  if (!AllBinary({cells.values().data(), static_cast<size_t>(cells.values_size())})) return;
  std::vector<std::pair<uint64_t, float>> indexed(cells.values_size());
  for (int i = 0; i < cells.values_size(); ++i) {
    const uint32_t x = cells.cells().x(i), y = cells.cells().y(i), z = cells.cells().z(i);
    if (x >= grid_.x || y >= grid_.y || z >= grid_.z) return;  // the daemon rejects it by its index
    indexed[i] = {x + uint64_t{grid_.x} * (y + uint64_t{grid_.y} * z), cells.values(i)};
  }
  std::sort(indexed.begin(), indexed.end());
  std::vector<uint64_t> indices(indexed.size());
  std::vector<float> values(indexed.size());
  for (size_t i = 0; i < indexed.size(); ++i) {
    if (i > 0 && indexed[i].first == indexed[i - 1].first) return;  // a cell twice: only CellObservations
    indices[i] = indexed[i].first;
    values[i] = indexed[i].second;
  }
  v1::CompactCells compact;
  compact.set_indices(EncodeIndexGaps(indices));
  compact.set_occupied(PackOccupiedBits(values));
  if (compact.ByteSizeLong() >= cells.ByteSizeLong()) return;
  *request_.mutable_compact() = std::move(compact);
}

ScanBuilder& ScanBuilder::AddPoint(Point point, float value) {
  if (!Use(Kind::kPoints, "AddPoint")) return *this;
  v1::PointObservations* points = request_.mutable_points();
  points->mutable_points()->add_x(point.x);
  points->mutable_points()->add_y(point.y);
  points->mutable_points()->add_z(point.z);
  points->add_values(value);
  ++observations_;
  return *this;
}

ScanBuilder& ScanBuilder::SetPatch(Cell origin, GridShape shape, std::vector<float> values) {
  if (!Use(Kind::kPatch, "SetPatch")) return *this;
  if (values.size() != shape.cells()) {
    error_ = absl::InvalidArgumentError(absl::StrCat("SetPatch: ", values.size(), " values for a patch of ", shape.x,
                                                     "×", shape.y, "×", shape.z, " = ", shape.cells(), " cells"));
    return *this;
  }
  v1::DensePatch* patch = request_.mutable_patch();
  SetPatchShape(origin, shape, *patch);
  patch->mutable_values()->Assign(values.begin(), values.end());
  observations_ = values.size();
  return *this;
}

ScanBuilder& ScanBuilder::SetPatchBytes(Cell origin, GridShape shape, std::string probabilities) {
  if (!Use(Kind::kPatch, "SetPatchBytes")) return *this;
  if (probabilities.size() != shape.cells()) {
    error_ =
        absl::InvalidArgumentError(absl::StrCat("SetPatchBytes: ", probabilities.size(), " bytes for a patch of ",
                                                shape.x, "×", shape.y, "×", shape.z, " = ", shape.cells(), " cells"));
    return *this;
  }
  v1::DensePatch* patch = request_.mutable_patch();
  SetPatchShape(origin, shape, *patch);
  observations_ = probabilities.size();
  patch->set_probabilities(std::move(probabilities));
  return *this;
}

ScanBuilder& ScanBuilder::AddState(uint64_t id, float value, const std::string& name, const std::string& group) {
  if (!Use(Kind::kStates, "AddState")) return *this;
  request_.mutable_states()->add_ids(id);
  request_.mutable_states()->add_values(value);
  names_.push_back(name);
  groups_.push_back(group);
  labelled_ |= !name.empty() || !group.empty();
  ++observations_;
  return *this;
}

ScanBuilder& ScanBuilder::AddNamedState(const std::string& name, float value, const std::string& group) {
  if (!Use(Kind::kNamedStates, "AddNamedState")) return *this;
  request_.mutable_named_states()->add_names(name);
  request_.mutable_named_states()->add_values(value);
  groups_.push_back(group);
  labelled_ |= !group.empty();
  ++observations_;
  return *this;
}

absl::StatusOr<Scan> ScanBuilder::Build() {
  absl::Status error = error_;
  const double time = request_.time();
  if (error.ok() && !(std::isfinite(time) && std::abs(time) <= kMaxAbsTime)) {
    error = absl::InvalidArgumentError(
        absl::StrCat("time is ", time, ": a scan's time must be finite seconds, |t| ≤ 1e13"));
  }
  if (error.ok() && observations_ == 0)
    error = absl::InvalidArgumentError("the scan has no observations: add some first");
  Scan scan;
  if (error.ok()) {
    // Names and groups go on the wire only when some are set: they are either empty or one per state.
    if (labelled_ && kind_ == Kind::kStates) {
      for (std::string& name : names_) request_.mutable_states()->add_names(std::move(name));
      for (std::string& group : groups_) request_.mutable_states()->add_groups(std::move(group));
    } else if (labelled_ && kind_ == Kind::kNamedStates) {
      for (std::string& group : groups_) request_.mutable_named_states()->add_groups(std::move(group));
    }
    MaybeCompact();
    scan.request = std::move(request_);
    scan.observations = observations_;
  }
  // Empty again, at the same time, for the next scan.
  request_ = v1::IngestRequest();
  request_.set_time(time);
  kind_ = Kind::kNone;
  observations_ = 0;
  labelled_ = false;
  names_.clear();
  groups_.clear();
  error_ = absl::OkStatus();
  if (!error.ok()) return error;
  return scan;
}

}  // namespace fremen::client
