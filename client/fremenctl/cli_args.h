// Parsing of fremenctl's argument values that CLI11 cannot check alone: times ("now", seconds, or
// RFC 3339), grid cells "X,Y[,Z]" and metric points "X,Y[,Z]". Errors name the value and the form
// expected. Thread-safety: pure functions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "client/lib/state_set.h"

namespace fremen::client {

// Seconds since the Unix epoch: "now", a number ("1700000000.5"), or RFC 3339
// ("2026-11-23T08:00:00Z", "2026-11-23T08:00:00+01:00"). `now` is what "now" means.
absl::StatusOr<double> ParseTimeArg(absl::string_view text, absl::Time now = absl::Now());
absl::StatusOr<Cell> ParseCellArg(absl::string_view text);
absl::StatusOr<Point> ParsePointArg(absl::string_view text);

// The states named on a command line: exactly one of the lists non-empty (--cell X,Y[,Z],
// --point X,Y[,Z], --id N, --name S; each may repeat).
struct StateArgs {
  std::vector<std::string> cells, points, names;
  std::vector<uint64_t> ids;
};
absl::StatusOr<StateSet> ParseStateArgs(const StateArgs& args);
// The times named on a command line (ParseTimeArg each); at least one.
absl::StatusOr<std::vector<double>> ParseTimeArgs(const std::vector<std::string>& texts, absl::Time now = absl::Now());

}  // namespace fremen::client
