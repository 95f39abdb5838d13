// A history: observations that each carry their own time — a robot's log uploaded, a dataset
// imported — as one ingest batch instead of one batch per time (IngestRequest.history, generic
// maps). The daemon applies it exactly as one scan per run of consecutive observations with the
// same time, in the order added, so add a log in time order to get the model of the robot that
// streamed it.
//
// One state's history (ForId, ForName: Add(time, value)) goes on the wire with its id or name once;
// many states' (the default constructor: AddState(time, id, value)) with an id per observation.
// Values are not checked (the daemon rejects bad ones one by one, as for scans); times are, by
// Build. Cut a long log into batches of at most kHistoryBatchObservations, which stays far below
// the daemon's default 16 MiB message limit (≤ 20 bytes an observation) while one batch's log
// record and acknowledgement are shared by many observations.
// Thread-compatible.
#pragma once

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/lib/scan_builder.h"
#include "fremen/v1/ingest.pb.h"

namespace fremen::client {

inline constexpr uint64_t kHistoryBatchObservations = 1u << 18;

class HistoryBuilder {
 public:
  // Many states' history, by id: AddState.
  HistoryBuilder() = default;
  // One state's history: Add. `name` and `group` label the state as in ScanBuilder::AddState.
  static HistoryBuilder ForId(uint64_t id, const std::string& name = "", const std::string& group = "");
  // One state's history by name (a name seen for the first time becomes a new state): Add.
  static HistoryBuilder ForName(const std::string& name, const std::string& group = "");

  // An observation of the builder's state (ForId, ForName).
  HistoryBuilder& Add(double time, float value);
  // An observation of state `id` (the default constructor).
  HistoryBuilder& AddState(double time, uint64_t id, float value);

  // Observations added so far.
  uint64_t size() const { return static_cast<uint64_t>(request_.history().values_size()); }

  // The batch, or INVALID_ARGUMENT saying what is wrong: no observations, a time that is not finite
  // seconds in [0, 1e13] (naming its index), Add on a many-states builder or AddState on a
  // one-state one. The builder is left empty, for the same state(s).
  absl::StatusOr<Scan> Build();

 private:
  enum class Kind { kManyStates, kOneState };
  void Misuse(const char* what);

  Kind kind_ = Kind::kManyStates;
  v1::IngestRequest request_;  // history's ids/names/groups hold the one state's, when kOneState
  absl::Status error_;
};

}  // namespace fremen::client
