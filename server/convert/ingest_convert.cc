#include "server/convert/ingest_convert.h"

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"
#include "storage/model/kernels/cpu_dispatch.h"
#include "storage/model/observation.h"
#include "storage/state_names.h"

namespace fremen::server {

namespace {

using storage::MapInfo;
using storage::MapKind;
using storage::ObservationBatch;

const std::string& NoLabel() {
  static const std::string* const none = new std::string();
  return *none;
}

absl::Status Invalid(absl::string_view message) { return absl::InvalidArgumentError(message); }

// "<field> has <got> <items> for <expected> <of>", when the lengths differ.
absl::Status CheckLength(absl::string_view field, size_t got, absl::string_view items, size_t expected,
                         absl::string_view of) {
  if (got == expected) return absl::OkStatus();
  return Invalid(absl::StrCat(field, " has ", got, " ", items, " for ", expected, " ", of));
}

// An array that is either empty or one per item.
absl::Status CheckOptionalLength(absl::string_view field, size_t got, absl::string_view items, size_t expected,
                                 absl::string_view of) {
  if (got == 0 || got == expected) return absl::OkStatus();
  return Invalid(absl::StrCat(field, " has ", got, " ", items, " for ", expected, " ", of, " (empty or one per ",
                              of.substr(0, of.size() - 1), ")"));
}

// storage::ValidateBatch checks the same limit; checked here too so that the message names the
// proto's field rather than storage's labels[i].
absl::Status CheckLabel(absl::string_view field, int i, const std::string& text) {
  if (text.size() <= storage::kMaxLabelLength) return absl::OkStatus();
  return Invalid(absl::StrCat(field, "[", i, "] has ", text.size(), " bytes; at most ", storage::kMaxLabelLength, " allowed"));
}

// The labels of a message whose names and groups are each empty or one per state (lengths checked
// already): label i, unless both are empty, is of state key_of(i). `message` ("states",
// "history") names the fields in errors.
template <typename KeyOf>
absl::Status AddLabels(absl::string_view message, const google::protobuf::RepeatedPtrField<std::string>& names,
                       const google::protobuf::RepeatedPtrField<std::string>& groups, KeyOf key_of,
                       ObservationBatch& batch) {
  for (int i = 0; i < names.size() || i < groups.size(); ++i) {
    const std::string& name = names.empty() ? NoLabel() : names[i];
    const std::string& group = groups.empty() ? NoLabel() : groups[i];
    if (name.empty() && group.empty()) continue;
    if (auto s = CheckLabel(absl::StrCat(message, ".names"), i, name); !s.ok()) return s;
    if (auto s = CheckLabel(absl::StrCat(message, ".groups"), i, group); !s.ok()) return s;
    batch.labels.push_back({key_of(i), name, group});
  }
  return absl::OkStatus();
}

absl::Status CheckKind(const MapInfo& map, absl::string_view what, MapKind wanted) {
  if (map.kind == wanted) return absl::OkStatus();
  return Invalid(absl::StrCat(what, " ", wanted == MapKind::kGrid ? "are only for grid maps" : "are only for generic maps",
                              "; map \"", map.name, "\" is a ", map.kind == MapKind::kGrid ? "grid" : "generic",
                              " map"));
}

template <typename Values>
void CopyValues(const Values& values, ObservationBatch& batch) {
  batch.values.assign(values.begin(), values.end());
}

// The keys of cells (x[i], y[i], z[i]) — z[i] = 0 without z — and kOutsideMapKey for a cell outside
// the grid (checked here, not left to the store: indices beyond 2^21 would alias inside the grid
// once packed). Branch-free, with the key layout fixed at compile time, so that the loop vectorises:
// about 1.5 ns a cell instead of 10, a tenth of a core at 10M cells/s.
template <bool kFlat, bool kHasZ>
void CellKeys(const storage::GridGeometry& grid, const uint32_t* x, const uint32_t* y, const uint32_t* z, size_t n,
              uint64_t* keys) {
  const storage::GridKeys layout = storage::GridKeys::For(kFlat ? 1 : 2);
  const uint32_t nx = grid.size[0], ny = grid.size[1], nz = grid.size[2];
  for (size_t i = 0; i < n; ++i) {
    const uint32_t cz = kHasZ ? z[i] : 0;
    const bool inside = (x[i] < nx) & (y[i] < ny) & (cz < nz);
    const uint64_t key = layout.Key(x[i], y[i], cz);
    keys[i] = inside ? key : kOutsideMapKey;
  }
}

// CellKeys for each key layout, each compiled for AVX2 too and chosen when the binary is loaded
// (storage/model/kernels/cpu_dispatch.h): four keys a vector instead of the portable build's two
// (a key is three 64-bit bit spreads; the conversion was 8 % of fremend's samples under 1000-cell
// scans of a 3-D grid).
using CellKeysFn = void(const storage::GridGeometry&, const uint32_t*, const uint32_t*, const uint32_t*, size_t,
                        uint64_t*);
FREMEN_KERNEL_CLONES void FlatCellKeys(const storage::GridGeometry& grid, const uint32_t* x, const uint32_t* y,
                                       const uint32_t* z, size_t n, uint64_t* keys) {
  CellKeys<true, false>(grid, x, y, z, n, keys);
}
FREMEN_KERNEL_CLONES void FlatCellKeysWithZ(const storage::GridGeometry& grid, const uint32_t* x, const uint32_t* y,
                                            const uint32_t* z, size_t n, uint64_t* keys) {
  CellKeys<true, true>(grid, x, y, z, n, keys);
}
FREMEN_KERNEL_CLONES void CubicCellKeys(const storage::GridGeometry& grid, const uint32_t* x, const uint32_t* y,
                                        const uint32_t* z, size_t n, uint64_t* keys) {
  CellKeys<false, false>(grid, x, y, z, n, keys);
}
FREMEN_KERNEL_CLONES void CubicCellKeysWithZ(const storage::GridGeometry& grid, const uint32_t* x, const uint32_t* y,
                                             const uint32_t* z, size_t n, uint64_t* keys) {
  CellKeys<false, true>(grid, x, y, z, n, keys);
}

absl::Status FromCells(const MapInfo& map, const v1::CellObservations& cells, ObservationBatch& batch) {
  const auto& x = cells.cells().x();
  const auto& y = cells.cells().y();
  const auto& z = cells.cells().z();
  const size_t n = x.size();
  if (auto s = CheckLength("cells.cells.y", y.size(), "indices", n, "cells (cells.cells.x)"); !s.ok()) return s;
  if (auto s = CheckOptionalLength("cells.cells.z", z.size(), "indices", n, "cells"); !s.ok()) return s;
  if (auto s = CheckLength("cells.values", cells.values_size(), "values", n, "cells"); !s.ok()) return s;
  batch.keys.resize(n);
  const bool flat = map.grid.keys().flat();
  CellKeysFn* const fill =
      flat ? (z.empty() ? FlatCellKeys : FlatCellKeysWithZ) : (z.empty() ? CubicCellKeys : CubicCellKeysWithZ);
  fill(map.grid, x.data(), y.data(), z.data(), n, batch.keys.data());
  batch.keys_from_grid.set = true;
  CopyValues(cells.values(), batch);
  return absl::OkStatus();
}

absl::Status FromPoints(const MapInfo& map, const v1::PointObservations& points, ObservationBatch& batch) {
  const auto& x = points.points().x();
  const auto& y = points.points().y();
  const auto& z = points.points().z();
  const size_t n = x.size();
  if (auto s = CheckLength("points.points.y", y.size(), "coordinates", n, "points (points.points.x)"); !s.ok()) {
    return s;
  }
  if (auto s = CheckOptionalLength("points.points.z", z.size(), "coordinates", n, "points"); !s.ok()) return s;
  if (auto s = CheckLength("points.values", points.values_size(), "values", n, "points"); !s.ok()) return s;
  const storage::GridKeys keys = map.grid.keys();
  batch.keys.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const auto cell = map.grid.CellOf(x[i], y[i], z.empty() ? 0.0 : z[i]);
    batch.keys[i] = cell ? keys.Key((*cell)[0], (*cell)[1], (*cell)[2]) : kOutsideMapKey;
  }
  batch.keys_from_grid.set = true;
  CopyValues(points.values(), batch);
  return absl::OkStatus();
}

absl::Status FromStates(const v1::StateObservations& states, ObservationBatch& batch) {
  const size_t n = states.ids_size();
  if (auto s = CheckLength("states.values", states.values_size(), "values", n, "ids"); !s.ok()) return s;
  if (auto s = CheckOptionalLength("states.names", states.names_size(), "names", n, "ids"); !s.ok()) return s;
  if (auto s = CheckOptionalLength("states.groups", states.groups_size(), "groups", n, "ids"); !s.ok()) return s;
  batch.keys.assign(states.ids().begin(), states.ids().end());
  CopyValues(states.values(), batch);
  return AddLabels("states", states.names(), states.groups(), [&](int i) { return states.ids(i); }, batch);
}

absl::Status FromNamedStates(const v1::NamedStateObservations& named, ObservationBatch& batch) {
  const size_t n = named.names_size();
  if (auto s = CheckLength("named_states.values", named.values_size(), "values", n, "names"); !s.ok()) return s;
  if (auto s = CheckOptionalLength("named_states.groups", named.groups_size(), "groups", n, "names"); !s.ok()) {
    return s;
  }
  batch.keys.resize(n);
  batch.labels.resize(n);
  for (int i = 0; i < named.names_size(); ++i) {
    const std::string& name = named.names(i);
    if (name.empty()) return Invalid(absl::StrCat("named_states.names[", i, "] is empty; every state needs a name"));
    if (auto s = CheckLabel("named_states.names", i, name); !s.ok()) return s;
    const std::string& group = named.groups_size() > 0 ? named.groups(i) : NoLabel();
    if (auto s = CheckLabel("named_states.groups", i, group); !s.ok()) return s;
    batch.keys[i] = storage::StateIdOfName(name);
    // Every time, not only the first: the client cannot know which batch mentions a name first, and
    // the store keeps a state's first label.
    batch.labels[i] = {batch.keys[i], name, group};
  }
  CopyValues(named.values(), batch);
  return absl::OkStatus();
}

// One state's history (a single id) or many states' (an id per value), each observation with its
// own time; the request's time must stay unset. The times are checked here so that the message
// names history.times rather than the store's times.
absl::Status FromHistory(const v1::IngestRequest& request, ObservationBatch& batch) {
  const v1::HistoryObservations& history = request.history();
  const size_t n = history.values_size();
  if (request.time() != 0) {
    return Invalid(absl::StrCat("time must be 0 (unset) with history, whose observations carry their own times "
                                "(history.times); got ",
                                request.time()));
  }
  if (auto s = CheckLength("history.times", history.times_size(), "times", n, "values"); !s.ok()) return s;
  // The states: by ids, which names and groups label, or, without ids, by names, as named_states.
  const bool by_name = history.ids_size() == 0 && history.names_size() > 0;
  const size_t ids = by_name ? history.names_size() : history.ids_size();
  const absl::string_view id_field = by_name ? "history.names" : "history.ids";
  if (ids != 1) {
    if (auto s = CheckLength(id_field, ids, by_name ? "names" : "ids", n, "values (or exactly 1: one state's history)");
        !s.ok()) {
      return s;
    }
  }
  if (!by_name) {
    if (auto s = CheckOptionalLength("history.names", history.names_size(), "names", ids, "ids"); !s.ok()) return s;
  }
  if (auto s = CheckOptionalLength("history.groups", history.groups_size(), "groups", ids, by_name ? "names" : "ids");
      !s.ok()) {
    return s;
  }
  const double* times = history.times().data();
  for (size_t i = 0; i < n; ++i) {
    if (!(times[i] >= 0.0 && times[i] <= model::kMaxAbsTime)) {
      return storage::CheckTime(times[i], absl::StrCat("history.times[", i, "]"));
    }
  }
  batch.times.assign(history.times().begin(), history.times().end());
  UninitializedVector<uint64_t> keys(ids);
  for (size_t i = 0; i < ids; ++i) {
    if (by_name && history.names(i).empty()) {
      return Invalid(absl::StrCat("history.names[", i, "] is empty; every state needs a name"));
    }
    keys[i] = by_name ? storage::StateIdOfName(history.names(i)) : history.ids(i);
  }
  // One state's key is kept apart from batch.keys: a history without values labels its state all
  // the same, and then batch.keys is empty.
  const uint64_t only_key = ids == 1 ? keys[0] : 0;
  if (ids == 1) {
    batch.keys.assign(n, only_key);
  } else {
    batch.keys = std::move(keys);
  }
  CopyValues(history.values(), batch);
  return AddLabels("history", history.names(), history.groups(),
                   [&](int i) { return ids == 1 ? only_key : batch.keys[i]; }, batch);
}

// x·y·z, saturated: a patch of 2^32 cells along each axis must not wrap around to a small count.
uint64_t CellCount(const std::array<uint32_t, 3>& size) {
  uint64_t count = 1;
  for (uint32_t s : size) {
    if (s != 0 && count > std::numeric_limits<uint64_t>::max() / s) return std::numeric_limits<uint64_t>::max();
    count *= s;
  }
  return count;
}

absl::Status FromPatch(const v1::DensePatch& patch, ObservationBatch& batch) {
  storage::DensePatch& out = batch.patch;
  out.origin = {patch.origin().x(), patch.origin().y(), patch.origin().z()};
  // An unset z is one layer, as in a grid's size.
  out.size = {patch.size().x(), patch.size().y(), patch.size().z() == 0 ? 1u : patch.size().z()};
  if (out.size[0] == 0 || out.size[1] == 0) {
    return Invalid(absl::StrCat("patch.size must be at least 1 along x and y, got ", out.size[0], "×", out.size[1]));
  }
  const uint64_t cells = CellCount(out.size);
  const std::string of = absl::StrCat("cells (patch.size ", out.size[0], "×", out.size[1], "×", out.size[2], ")");
  const bool bytes = !patch.probabilities().empty();
  if (bytes && patch.values_size() > 0) {
    return Invalid("patch: set values or probabilities, not both");
  }
  if (bytes) {
    if (auto s = CheckLength("patch.probabilities", patch.probabilities().size(), "bytes", cells, of); !s.ok()) return s;
    out.values.resize(cells);
    const auto* p = reinterpret_cast<const uint8_t*>(patch.probabilities().data());
    for (size_t i = 0; i < cells; ++i) out.values[i] = p[i] / 255.0f;  // exactly rounded: 51 → 0.2f
    return absl::OkStatus();
  }
  if (auto s = CheckLength("patch.values", patch.values_size(), "values", cells, of); !s.ok()) return s;
  out.values.assign(patch.values().begin(), patch.values().end());
  return absl::OkStatus();
}

// The bytes as they came (the log keeps them), then their expansion into keys and values.
absl::Status FromCompact(const MapInfo& map, const v1::CompactCells& compact, ObservationBatch& batch) {
  batch.compact.indices = compact.indices();
  batch.compact.occupied = compact.occupied();
  batch.compact.probabilities = compact.probabilities();
  return storage::ExpandCompact(map, batch);
}

absl::Status FillObservations(const MapInfo& map, const v1::IngestRequest& request, ObservationBatch& batch) {
  switch (request.observations_case()) {
    case v1::IngestRequest::kCells:
      if (auto s = CheckKind(map, "cells", MapKind::kGrid); !s.ok()) return s;
      return FromCells(map, request.cells(), batch);
    case v1::IngestRequest::kPoints:
      if (auto s = CheckKind(map, "points", MapKind::kGrid); !s.ok()) return s;
      return FromPoints(map, request.points(), batch);
    case v1::IngestRequest::kPatch:
      if (auto s = CheckKind(map, "patch observations", MapKind::kGrid); !s.ok()) return s;
      return FromPatch(request.patch(), batch);
    case v1::IngestRequest::kCompact:
      if (auto s = CheckKind(map, "compact cells", MapKind::kGrid); !s.ok()) return s;
      return FromCompact(map, request.compact(), batch);
    case v1::IngestRequest::kStates:
      if (auto s = CheckKind(map, "states by id", MapKind::kGeneric); !s.ok()) return s;
      return FromStates(request.states(), batch);
    case v1::IngestRequest::kNamedStates:
      if (auto s = CheckKind(map, "named_states", MapKind::kGeneric); !s.ok()) return s;
      return FromNamedStates(request.named_states(), batch);
    case v1::IngestRequest::kHistory:
      if (auto s = CheckKind(map, "history observations", MapKind::kGeneric); !s.ok()) return s;
      return FromHistory(request, batch);
    case v1::IngestRequest::OBSERVATIONS_NOT_SET:
      break;
  }
  return Invalid(
      "observations are required: one of cells, points, states, named_states, patch, compact or history");
}

v1::RejectReason ReasonToProto(storage::RejectReason reason) {
  switch (reason) {
    case storage::RejectReason::kValueOutOfRange: return v1::REJECT_REASON_VALUE_OUT_OF_RANGE;
    case storage::RejectReason::kOutsideMap: return v1::REJECT_REASON_OUTSIDE_MAP;
  }
  return v1::REJECT_REASON_UNSPECIFIED;
}

}  // namespace

absl::StatusOr<ObservationBatch> BatchFromRequest(const MapInfo& map, const v1::IngestRequest& request) {
  ObservationBatch batch;
  batch.writer_id = request.writer_id();
  batch.sequence = request.sequence();
  batch.time = request.time();
  if (absl::Status s = FillObservations(map, request, batch); !s.ok()) return s;
  return batch;
}

void AckToResponse(const storage::BatchAck& ack, v1::IngestResponse& out) {
  if (!ack.error.ok()) return ErrorToResponse(ack.sequence, ack.error, out);
  out.set_sequence(ack.sequence);
  out.set_accepted(ack.accepted);
  out.set_rejected(ack.rejected);
  out.set_duplicate(ack.duplicate);
  for (const storage::Rejection& r : ack.rejections) {
    v1::Rejection* rejection = out.add_rejections();
    rejection->set_index(r.index);
    rejection->set_reason(ReasonToProto(r.reason));
  }
}

void ErrorToResponse(uint64_t sequence, const absl::Status& error, v1::IngestResponse& out) {
  out.set_sequence(sequence);
  out.mutable_error()->set_code(static_cast<int>(error.code()));
  out.mutable_error()->set_message(std::string(error.message()));
}

}  // namespace fremen::server
