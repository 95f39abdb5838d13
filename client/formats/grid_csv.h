// CSV files of grid observations, one per line: `time,x,y,state` (2-D) or `time,x,y,z,state`
// (3-D); time in seconds, x/y/z integer cell indices, state in [0, 1]. An optional header line
// names the columns (time,x,y[,z],state); blank lines and lines starting with '#' are skipped.
// No threads; functions touch only the named file.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/formats/observation_batches.h"

namespace fremen::formats {

// Every observation of the file. Errors name `path:line` and the field ("grid.csv:7: field x:
// expected a cell index (an integer in [0, 4294967295]), got \"-1\""); a file whose lines mix 4 and
// 5 columns, or that holds no observation, is an error.
absl::StatusOr<std::vector<CellObservation>> ReadGridCsv(const std::string& path);
// The same from a stream; errors name `name`.
absl::StatusOr<std::vector<CellObservation>> ReadGridCsv(std::istream& in, const std::string& name);

}  // namespace fremen::formats
