// A batch of observations: one time, many states (one robot scan), or a history (a time per
// observation: a robot's log, an imported dataset), from one writer with a sequence number. The unit of the write path: validated, logged, applied and acknowledged whole.
//
// States are given by key (storage/cell_key.h: Morton code of a grid cell, or a generic state's id)
// or, for grids, as a dense patch (a box of cells, values x fastest, then y, then z). Generic states
// may be labelled with a name and a group in the batch that first mentions them.
// Value types.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "base/uninitialized_vector.h"
#include "storage/compact_cells.h"
#include "storage/map_info.h"

namespace fremen::storage {

struct DensePatch {
  std::array<uint32_t, 3> origin = {0, 0, 0};  // first cell
  std::array<uint32_t, 3> size = {0, 0, 0};    // cells along x, y, z
  std::vector<float> values;                   // size x·y·z, x fastest
  bool operator==(const DensePatch&) const = default;
};

struct StateLabel {
  uint64_t key = 0;
  std::string name;   // may be empty
  std::string group;  // may be empty
  bool operator==(const StateLabel&) const = default;
};

struct ObservationBatch {
  // Who sent it and its place in that writer's sequence: a batch whose (writer, sequence) was
  // already applied is acknowledged again, not applied again.
  uint64_t writer_id = 0;
  uint64_t sequence = 0;
  double time = 0;
  // Sized, then written whole, by whatever fills them (the compact scan's expansion above all):
  // their resize does not zero-fill (base/uninitialized_vector.h).
  UninitializedVector<uint64_t> keys;
  UninitializedVector<float> values;  // one per key
  // Cells in the API's compact form, when they came so: keys and values are then its expansion
  // (ExpandCompact), and the log keeps this form instead of them.
  CompactCells compact;
  // Set by what made the keys from cell indices (the API's conversions, ExpandCompact): every key
  // is a cell's inside the grid or kNotACellKey, so that Classify need not decode each key to
  // check it (a tenth of the ingest path's instructions). Not content: neither logged nor compared;
  // a batch decoded from a version 1 record has it unset and is checked key by key, to the same
  // result.
  struct KeysFromGrid {
    bool set = false;
    // How many keys are kNotACellKey, when what made them counted them (the compact expansion):
    // then Classify need not read the keys at all.
    std::optional<size_t> outside;
    bool operator==(const KeysFromGrid&) const { return true; }
  } keys_from_grid;
  DensePatch patch;           // empty when size has a zero
  std::vector<StateLabel> labels;
  // A history: empty for a scan (every observation at `time`), else one time per key, `time` 0 and
  // no patch. Applied as one scan per run of consecutive keys with the same time, in order.
  std::vector<double> times;

  bool is_history() const { return !times.empty(); }

  size_t observation_count() const {
    return keys.size() + size_t{patch.size[0]} * patch.size[1] * patch.size[2];
  }
  bool operator==(const ObservationBatch&) const = default;
};

// Why an observation was not applied.
enum class RejectReason : uint8_t {
  kValueOutOfRange = 1,  // NaN or outside [0, 1]
  kOutsideMap = 2,       // a cell outside the grid
};

struct Rejection {
  uint32_t index;  // position in keys, then in the patch (keys.size() + patch offset)
  RejectReason reason;
};

struct BatchAck {
  uint64_t sequence = 0;
  uint64_t accepted = 0;
  uint64_t rejected = 0;
  // The first rejections (at most kMaxReportedRejections), for the client to fix its input.
  std::vector<Rejection> rejections;
  // The batch had been applied before (a retry): nothing was applied this time.
  bool duplicate = false;
  // Not OK when the batch was refused as a whole and nothing of it applied, while the map goes on:
  // AlreadyExists when its (writer, sequence) was used for another batch (storage/dedup_table.h).
  absl::Status error;
  uint64_t lsn = 0;  // its place in the map's log
};

inline constexpr size_t kMaxReportedRejections = 16;
// The longest name or group of a state, bytes.
inline constexpr size_t kMaxLabelLength = 256;

// The times the service accepts, for observations and for queries alike: seconds since the Unix
// epoch, finite, in [0, 1e13] (docs/model.md, "Observations": NaN, infinite, negative or absurd
// times are bad input; the model maths itself accepts ±1e13). InvalidArgument naming `field`
// otherwise.
absl::Status CheckTime(double t, absl::string_view field);

// Checks what makes the whole batch unusable (the message names the field): the time (CheckTime), mismatched lengths, a patch outside the grid or with the wrong value count,
// labels on a grid; for a history also every time (CheckTime, "times[i]"), a time or a patch beside
// the times, and a grid map (histories are for generic maps). Per-observation problems are not errors: see Classify.
absl::Status ValidateBatch(const MapInfo& map, const ObservationBatch& batch);

// Marks each observation accepted or rejected; `accept[i]` for i over keys then patch cells.
BatchAck Classify(const MapInfo& map, const ObservationBatch& batch, std::vector<uint8_t>& accept);

// Fills keys and values from a non-empty batch.compact (a grid map only); InvalidArgument naming
// the field (compact.indices, ...) when it is malformed. OK and nothing done when compact is empty.
absl::Status ExpandCompact(const MapInfo& map, ObservationBatch& batch);

// Log payload encoding: version 2 when batch.compact is set (its bytes as they came, not keys and
// values), version 3 for a history (version 1's fields, then the times), version 1 otherwise, so
// that a batch of the other kinds keeps its bytes and fingerprint. DecodeBatch reads all three; a
// version 2 batch comes back with compact set and keys empty, for ExpandCompact. Decode answers
// DataLoss on damaged bytes.
std::string EncodeBatch(const ObservationBatch& batch);
absl::StatusOr<ObservationBatch> DecodeBatch(std::string_view bytes);

// What tells a retry of a batch from another batch under the same (writer, sequence): XXH3-64 of
// its EncodeBatch bytes (the conversion from a request is deterministic, so a resent request gives
// the same bytes). Persisted in checkpoints: the hash must never change.
uint64_t BatchFingerprint(std::string_view encoded);

}  // namespace fremen::storage
