// fremen.v1.IngestRequest → storage::ObservationBatch, and storage's acknowledgement → IngestResponse.
//
// The proto's rules the store does not know are checked here, with messages naming the proto's
// field ("cells.values has 3 values for 4 cells"): parallel arrays of equal length, the kind of
// observations the map takes (cells, points and patches for grids; ids and names for generic
// maps), exactly one of a patch's values and probabilities. What the store checks itself (the time,
// a patch inside the grid) is left to MapStore::Submit, whose messages already name those fields.
//
// A single cell outside the grid (by index or by point) is not a batch error but one rejected
// observation: it gets kOutsideMapKey, a key that is no cell's key, which the store's Classify
// rejects as OUTSIDE_MAP like any other cell outside the map.
// Pure functions; thread-safe.
#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fremen/v1/ingest.pb.h"
#include "storage/batch.h"
#include "storage/map_info.h"

namespace fremen::server {

// No cell has this key (3-D Morton keys use 63 bits, 2-D ones 42), so the store rejects it as
// outside the map: storage's own key for that.
inline constexpr uint64_t kOutsideMapKey = storage::kNotACellKey;

// The batch `request` describes for `map`; InvalidArgument naming the field when it is unusable as
// a whole.
absl::StatusOr<storage::ObservationBatch> BatchFromRequest(const storage::MapInfo& map,
                                                           const v1::IngestRequest& request);

// The response acknowledging a batch (or refusing it, when the store refused it: ack.error).
void AckToResponse(const storage::BatchAck& ack, v1::IngestResponse& out);

// The response refusing batch `sequence` as a whole.
void ErrorToResponse(uint64_t sequence, const absl::Status& error, v1::IngestResponse& out);

}  // namespace fremen::server
