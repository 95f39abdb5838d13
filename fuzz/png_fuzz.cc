// PNG decoding (client/formats/png_decode.h DecodePng: 8-bit gray and RGB, all row filters). An
// image that decodes has width · height · channels pixels, and the encoder's PNG of it decodes to
// the same pixels. Input: the file's bytes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "client/formats/png.h"
#include "client/formats/png_decode.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  auto image = formats::DecodePng(std::string(fuzz::AsView(data, size)));
  if (!image.ok()) return 0;
  FUZZ_CHECK(image->pixels.size() == static_cast<size_t>(image->width) * image->height * image->channels,
             "width · height · channels bytes");
  auto encoded = formats::EncodePng(*image);
  FUZZ_CHECK(encoded.ok(), encoded.status().ToString());
  auto again = formats::DecodePng(*encoded);
  FUZZ_CHECK(again.ok() && again->pixels == image->pixels && again->width == image->width, "PNG round trip");
  return 0;
}
