// GET /v1/maps/{map}/region.png: one z-plane of PredictRegion drawn as a gray PNG, so that `curl`
// or an <img> tag shows a predicted map. Query parameters: PredictRegionRequest's (lo.*, hi.*,
// time, confidence, options.*) and `mode`:
//   probability (the default)  gray = 255 · (1 − p): occupied dark, free light
//   entropy                    gray = 255 · (1 − H(p)): certain cells light, uncertain dark
//   state                      p ≥ confidence: 0 (occupied), else 255 (free)
// all with base/gray_levels.h, as fremenctl draws its PNG files. The picture is hi.x − lo.x wide
// and hi.y − lo.y high; row 0 is the highest y (image up = +y, as a map is looked at).
// Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "fremen/v1/query.pb.h"

namespace fremen::server {

// The PredictRegion call a region.png query asks for (the output set by `mode`). InvalidArgument
// naming the parameter: an unknown mode, `output` given (mode says it), several z-planes.
absl::StatusOr<v1::PredictRegionRequest> RegionPngRequest(const std::multimap<std::string, std::string>& params);

// The picture's pixels, row 0 first, from the joined answer to `request`. InvalidArgument when
// the answer does not hold the request's box.
absl::StatusOr<std::vector<uint8_t>> RegionPngPixels(const v1::PredictRegionRequest& request,
                                                     const v1::PredictRegionResponse& region);

// The PNG file of RegionPngPixels.
absl::StatusOr<std::string> RegionPng(const v1::PredictRegionRequest& request, const v1::PredictRegionResponse& region);

}  // namespace fremen::server
