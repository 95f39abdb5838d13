// A scan: the observations a robot made at one time, as one ingest batch. ScanBuilder accumulates
// (cell, value), (point, value), (id, value) or (name, value) pairs — one kind per scan, as the
// API's batches hold one kind — or takes one dense patch, and builds the batch's request (the
// session sets map, writer and sequence).
//
// Values are observations s in [0, 1] (0 free/closed/absent, 1 occupied/open/present). The builder
// does not check them: the daemon rejects bad ones one by one and says which in the ack, so that
// a robot's accounting comes from one place.
// Thread-compatible.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/lib/state_set.h"
#include "fremen/v1/ingest.pb.h"

namespace fremen::client {

// A built scan, ready for IngestSession::Send.
struct Scan {
  v1::IngestRequest request;  // time and observations; map, writer_id and sequence unset
  uint64_t observations = 0;
};

class ScanBuilder {
 public:
  // `time`: when the scan was taken, seconds (REQUIRES: finite, |time| ≤ 1e13 — checked by Build).
  explicit ScanBuilder(double time);

  // Grid maps.
  ScanBuilder& AddCell(Cell cell, float value);
  ScanBuilder& AddPoint(Point point, float value);
  // A dense box from `origin`, values x fastest, then y, then z: shape.cells() floats, or as many
  // bytes s = byte / 255 (a quarter of the size on the wire). A patch is the whole scan.
  ScanBuilder& SetPatch(Cell origin, GridShape shape, std::vector<float> values);
  ScanBuilder& SetPatchBytes(Cell origin, GridShape shape, std::string probabilities);
  // Generic maps. `name` and `group` label a state the first time the daemon sees it; a group is
  // what TopStates ranks within.
  ScanBuilder& AddState(uint64_t id, float value, const std::string& name = "", const std::string& group = "");
  ScanBuilder& AddNamedState(const std::string& name, float value, const std::string& group = "");

  // The map's grid size (GetMap's grid.size). With it, Build sends a scan of cells as CompactCells
  // (index gaps and one bit a value: about 1.1 bytes a binary observation instead of 7) when that
  // loses nothing and is smaller: every value 0 or 1, every cell inside `grid` and none twice. The
  // cells go sorted by index then, so an ack's rejection indices (none, for such a scan, unless
  // `grid` is not the map's) count in that order. Otherwise, and without a grid, CellObservations.
  ScanBuilder& SetGrid(GridShape grid);

  // Observations added so far.
  uint64_t size() const { return observations_; }

  // The scan, or INVALID_ARGUMENT saying what is wrong: kinds mixed, a bad time, an empty scan, a
  // patch whose values do not fill its shape. The builder is left empty.
  absl::StatusOr<Scan> Build();

 private:
  enum class Kind { kNone, kCells, kPoints, kPatch, kStates, kNamedStates };
  // Fixes the scan's kind at the first observation; records an error when another kind comes.
  bool Use(Kind kind, const char* what);
  // The cells as CompactCells in request_, when SetGrid's conditions hold.
  void MaybeCompact();

  v1::IngestRequest request_;
  Kind kind_ = Kind::kNone;
  uint64_t observations_ = 0;
  bool labelled_ = false;  // some AddState/AddNamedState had a name or group
  GridShape grid_;         // x = 0: no grid set
  std::vector<std::string> names_, groups_;
  absl::Status error_;
};

}  // namespace fremen::client
