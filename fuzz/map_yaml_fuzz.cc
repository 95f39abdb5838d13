// The map_server YAML (client/formats/map_yaml.h ParseMapYaml). Metadata that parses is what
// fremenctl then converts pixels with: every pixel value maps to an observation in [0, 1] or none,
// and every probability to a pixel. Input:
// the file's text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "client/formats/map_yaml.h"
#include "client/formats/occupancy_pixels.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  auto metadata = formats::ParseMapYaml(std::string(fuzz::AsView(data, size)), "fuzz.yaml");
  if (!metadata.ok()) return 0;
  FUZZ_CHECK(std::isfinite(metadata->resolution) && metadata->resolution > 0, "resolution is checked");
  for (int v = 0; v < 256; ++v) {
    const auto s = formats::ObservationFromPixel(static_cast<uint8_t>(v), *metadata);
    FUZZ_CHECK(!s || (*s >= 0 && *s <= 1), "an observation is in [0, 1]");
    const int cell = formats::CellFromPixel(static_cast<uint8_t>(v), *metadata);
    FUZZ_CHECK(cell >= formats::kCellUnknown && cell <= formats::kCellOccupied, "a cell is -1..100");
  }
  for (double p : {0.0, 0.196, 0.25, 0.5, 0.65, 1.0}) (void)formats::PixelFromProbability(p, *metadata);
  (void)formats::ResolveImagePath("/maps/fuzz.yaml", *metadata);
  return 0;
}
