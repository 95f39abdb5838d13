// PGM files (client/formats/pgm.h ParsePgm: P5 and P2, any maxval), as fremenctl ingest
// --map-server reads them. An image that parses has width · height · channels pixels and survives
// the P5 writer's format. Input: the file's bytes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "client/formats/pgm.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  auto image = formats::ParsePgm(std::string(fuzz::AsView(data, size)), "fuzz.pgm");
  if (!image.ok()) return 0;
  FUZZ_CHECK(image->channels == 1 && image->width > 0 && image->height > 0, "a gray image with pixels");
  FUZZ_CHECK(image->pixels.size() == static_cast<size_t>(image->width) * image->height, "one byte per pixel");
  return 0;
}
