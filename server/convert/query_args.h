// Checks of the scalar inputs of QueryService requests — times, confidences, prediction options,
// request sizes — each error naming the field the client sent ("times[3]", "options.order").
// Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <span>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "fremen/v1/common.pb.h"
#include "google/protobuf/repeated_field.h"
#include "storage/batch.h"
#include "storage/map_info.h"
#include "storage/queries.h"

namespace fremen::server {

// A packed repeated field as a span (no copy).
template <typename T>
std::span<const T> SpanOf(const google::protobuf::RepeatedField<T>& field) {
  return {field.data(), static_cast<size_t>(field.size())};
}

// The most (state, time) pairs one Predict or CheckAnomalies call may ask for: 2^21 answers as
// floats and bools are 10 MiB, which fits the default 16 MiB message limit with room to spare (a
// daemon configured with a smaller limit refuses larger answers with gRPC's own RESOURCE_EXHAUSTED).
inline constexpr uint64_t kMaxPredictions = uint64_t{1} << 21;

// InvalidArgument unless t is a time the service accepts: finite, in [0, 1e13] s.
using storage::CheckTime;
// The same for every element; the error names `field[i]`.
absl::Status CheckTimes(std::span<const double> times, absl::string_view field);
// InvalidArgument unless c is in [lo, hi] (NaN is not).
absl::Status CheckConfidence(float c, float lo, float hi, absl::string_view field);
// ResourceExhausted when states × times exceeds kMaxPredictions (the numbers in the message).
absl::Status CheckPredictionCount(uint64_t states, uint64_t times);

// The options as storage takes them. InvalidArgument naming `field`.order for an order above the
// map's L; FailedPrecondition naming `field`.persistence on a map kept without persistence.
absl::StatusOr<storage::PredictOptions> PredictOptionsOf(const storage::MapInfo& map,
                                                         const v1::PredictionOptions& options,
                                                         absl::string_view field);

}  // namespace fremen::server
