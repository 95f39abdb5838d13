// Test support: observations written into a stopped daemon's data directory with storage::Store
// itself, for end-to-end tests that need data without depending on the ingest service.
// REQUIRES: no daemon runs on the data directory meanwhile. Functions; thread-compatible.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/batch.h"

namespace fremen::testing {

// Writes every batch into `map` (which must exist), each acknowledged, then closes the store
// (which checkpoints). Writer id and sequence numbers are filled in.
absl::Status WriteBatches(const std::string& data_dir, const std::string& map,
                          std::vector<storage::ObservationBatch> batches);

// A scan of a generic map: states `ids` with `values` at time t.
storage::ObservationBatch GenericScan(const std::vector<uint64_t>& ids, const std::vector<float>& values, double t);
// A scan of a whole nx × ny grid, every cell `value`, at time t.
storage::ObservationBatch GridScan(uint32_t nx, uint32_t ny, double t, float value);

}  // namespace fremen::testing
