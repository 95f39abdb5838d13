#include "server/gateway/png_encode.h"

#include <png.h>

#include <csetjmp>

#include "absl/strings/str_cat.h"

namespace fremen::server {

namespace {

void AppendToString(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

void NoFlush(png_structp) {}

}  // namespace

absl::StatusOr<std::string> EncodeGrayPng(uint32_t width, uint32_t height, std::span<const uint8_t> pixels) {
  if (width == 0 || height == 0 || pixels.size() != static_cast<uint64_t>(width) * height) {
    return absl::InvalidArgumentError(
        absl::StrCat("a PNG of ", width, " × ", height, " pixels cannot hold ", pixels.size(), " values"));
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (png == nullptr) return absl::ResourceExhaustedError("libpng: cannot allocate the encoder");
  png_infop info = png_create_info_struct(png);
  std::string out;
  // libpng reports errors by longjmp to here; nothing with a destructor is created below this line.
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return absl::InternalError("libpng could not encode the image");
  }
  png_set_write_fn(png, &out, AppendToString, NoFlush);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (uint32_t y = 0; y < height; ++y) {
    png_write_row(png, const_cast<png_bytep>(pixels.data() + static_cast<size_t>(y) * width));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

}  // namespace fremen::server
