#include "server/convert/query_args.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "storage/model/observation.h"

namespace fremen::server {

absl::Status CheckTimes(std::span<const double> times, absl::string_view field) {
  for (size_t i = 0; i < times.size(); ++i) {
    // The field's name is only built for the bad time.
    if (!(times[i] >= 0.0 && times[i] <= model::kMaxAbsTime)) {
      return CheckTime(times[i], absl::StrCat(field, "[", i, "]"));
    }
  }
  return absl::OkStatus();
}

absl::Status CheckConfidence(float c, float lo, float hi, absl::string_view field) {
  if (c >= lo && c <= hi) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(field, " must be in [", lo, ", ", hi, "], got ", c));
}

absl::Status CheckPredictionCount(uint64_t states, uint64_t times) {
  // states and times are repeated-field sizes (< 2^31 each): the product cannot overflow.
  if (states * times <= kMaxPredictions) return absl::OkStatus();
  return absl::ResourceExhaustedError(absl::StrCat("states × times = ", states, " × ", times, " = ", states * times,
                                                   " predictions, more than the ", kMaxPredictions,
                                                   " one call may ask for; split the request"));
}

absl::StatusOr<storage::PredictOptions> PredictOptionsOf(const storage::MapInfo& map,
                                                         const v1::PredictionOptions& options,
                                                         absl::string_view field) {
  storage::PredictOptions out;
  if (options.has_order()) {
    if (options.order() > map.max_order) {
      return absl::InvalidArgumentError(absl::StrCat(field, ".order must be ≤ ", map.max_order,
                                                     " (the max_order of map ", map.name, "), got ",
                                                     options.order()));
    }
    out.order = static_cast<int>(options.order());
  }
  if (options.persistence()) {
    if (!map.persistence) {
      return absl::FailedPreconditionError(absl::StrCat(field, ".persistence: map ", map.name,
                                                        " was created without the persistence model"));
    }
    out.persistence = true;
  }
  return out;
}

}  // namespace fremen::server
