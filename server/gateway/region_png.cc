#include "server/gateway/region_png.h"

#include "absl/strings/str_cat.h"
#include "base/gray_levels.h"
#include "server/gateway/png_encode.h"
#include "server/gateway/request_fields.h"

namespace fremen::server {

absl::StatusOr<v1::PredictRegionRequest> RegionPngRequest(const std::multimap<std::string, std::string>& params) {
  std::multimap<std::string, std::string> fields = params;
  fields.erase("mode");
  if (fields.count("output") > 0) {
    return absl::InvalidArgumentError("query parameter output: region.png sets it from mode (probability, entropy or state)");
  }
  v1::PredictRegionRequest request;
  if (absl::Status s = SetFieldsFromQuery(fields, request); !s.ok()) return s;
  const auto mode = params.find("mode");
  const std::string name = mode == params.end() ? "probability" : mode->second;
  if (name == "probability") {
    request.set_output(v1::REGION_OUTPUT_FLOAT);
  } else if (name == "entropy") {
    request.set_output(v1::REGION_OUTPUT_ENTROPY);
  } else if (name == "state") {
    request.set_output(v1::REGION_OUTPUT_STATES);
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("query parameter mode: must be probability, entropy or state, got \"", name, "\""));
  }
  // lo.z = hi.z = 0 is a 2-D grid's one plane (PredictRegion's own rule).
  const uint32_t planes = request.hi().z() == 0 && request.lo().z() == 0 ? 1 : request.hi().z() - request.lo().z();
  if (request.hi().z() < request.lo().z() || planes != 1) {
    return absl::InvalidArgumentError(absl::StrCat("region.png draws one z-plane: hi.z − lo.z must be 1, got lo.z ",
                                                   request.lo().z(), " and hi.z ", request.hi().z()));
  }
  return request;
}

absl::StatusOr<std::vector<uint8_t>> RegionPngPixels(const v1::PredictRegionRequest& request,
                                                     const v1::PredictRegionResponse& region) {
  const uint32_t width = request.hi().x() - request.lo().x();
  const uint32_t height = request.hi().y() - request.lo().y();
  const uint64_t cells = static_cast<uint64_t>(width) * height;
  const bool floats = request.output() != v1::REGION_OUTPUT_STATES;
  const uint64_t values = floats ? region.float_values_size() : region.bytes_values().size();
  if (request.hi().x() < request.lo().x() || request.hi().y() < request.lo().y() || values != cells) {
    return absl::InvalidArgumentError(
        absl::StrCat("the region holds ", values, " values, not the ", width, " × ", height, " of the box"));
  }
  std::vector<uint8_t> pixels(cells);
  for (uint32_t y = 0; y < height; ++y) {
    const uint64_t row = static_cast<uint64_t>(height - 1 - y) * width;  // image up = +y
    for (uint32_t x = 0; x < width; ++x) {
      const uint64_t cell = static_cast<uint64_t>(y) * width + x;
      const double value = floats ? region.float_values(static_cast<int>(cell))
                                  : static_cast<double>(static_cast<uint8_t>(region.bytes_values()[cell]));
      pixels[row + x] = GrayLevel(value);
    }
  }
  return pixels;
}

absl::StatusOr<std::string> RegionPng(const v1::PredictRegionRequest& request, const v1::PredictRegionResponse& region) {
  auto pixels = RegionPngPixels(request, region);
  if (!pixels.ok()) return pixels.status();
  return EncodeGrayPng(request.hi().x() - request.lo().x(), request.hi().y() - request.lo().y(), *pixels);
}

}  // namespace fremen::server
