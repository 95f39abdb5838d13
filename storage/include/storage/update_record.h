// What a map's last update job did (docs/update-job.md, "What it records": when, how long, states
// updated, ε_p before/after, the histogram of chosen orders), kept by the map's store in the file
// <map dir>/last_update so that map statistics show it across restarts.
// Value type and pure functions, except WriteUpdateRecord/ReadUpdateRecord (file I/O through
// an Env); thread-safe.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/env/env.h"

namespace fremen::storage {

struct UpdateRecord {
  double start_time = 0;        // Unix seconds
  double duration_seconds = 0;
  uint64_t states_updated = 0;  // states observed since their last update, republished
  // The map's mean decayed ε_p at each state's selected order (docs/model.md, "Order selection")
  // before and after.
  double prediction_error_before = 0;
  double prediction_error_after = 0;
  // Dynamic states by selected order 0..L after the update.
  std::vector<uint64_t> order_histogram;
  bool operator==(const UpdateRecord&) const = default;
};

// Version byte, then the fields (doubles as IEEE bits, counts as varints).
std::string EncodeUpdateRecord(const UpdateRecord& record);
// DataLoss naming the field on truncated or corrupted bytes.
absl::StatusOr<UpdateRecord> DecodeUpdateRecord(std::string_view bytes);

// Replaces `path` atomically and durably (WriteFileAtomically).
absl::Status WriteUpdateRecord(Env* env, const std::string& path, const UpdateRecord& record);
// nullopt when the file does not exist; DataLoss when it cannot be decoded.
absl::StatusOr<std::optional<UpdateRecord>> ReadUpdateRecord(Env* env, const std::string& path);

}  // namespace fremen::storage
