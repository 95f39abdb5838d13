// PNG decoding (see png_decode.h).
#include "client/formats/png_decode.h"

#include <zlib.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace fremen::formats {

namespace {

uint32_t BigEndian32(const std::string& bytes, size_t at) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + at);
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

// The Paeth predictor of the PNG specification (ISO/IEC 15948, "Filter type 4: Paeth").
uint8_t Paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return static_cast<uint8_t>(a);
  if (pb <= pc) return static_cast<uint8_t>(b);
  return static_cast<uint8_t>(c);
}

}  // namespace

absl::StatusOr<Image> DecodePng(const std::string& bytes) {
  if (bytes.size() < 8 || bytes.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) {
    return absl::InvalidArgumentError("PNG: bad signature");
  }
  int width = 0, height = 0, channels = 0;
  std::string idat;
  bool seen_end = false;
  for (size_t at = 8; at < bytes.size() && !seen_end;) {
    if (bytes.size() - at < 12) return absl::InvalidArgumentError(absl::StrCat("PNG: truncated chunk at byte ", at));
    const uint32_t length = BigEndian32(bytes, at);
    if (bytes.size() - at - 12 < length) {
      return absl::InvalidArgumentError(absl::StrCat("PNG: chunk at byte ", at, " runs past the end"));
    }
    const std::string type = bytes.substr(at + 4, 4);
    const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(bytes.data() + at + 4), 4 + length);
    if (crc != BigEndian32(bytes, at + 8 + length)) {
      return absl::InvalidArgumentError(absl::StrCat("PNG: CRC mismatch in chunk ", type));
    }
    const std::string data = bytes.substr(at + 8, length);
    if (type == "IHDR") {
      if (length != 13) return absl::InvalidArgumentError("PNG: IHDR must be 13 bytes");
      width = static_cast<int>(BigEndian32(data, 0));
      height = static_cast<int>(BigEndian32(data, 4));
      const int depth = static_cast<unsigned char>(data[8]), colour = static_cast<unsigned char>(data[9]);
      if (depth != 8 || (colour != 0 && colour != 2) || data[10] != 0 || data[11] != 0 || data[12] != 0) {
        return absl::UnimplementedError("PNG: only 8-bit gray or RGB, non-interlaced images are supported");
      }
      if (width < 1 || height < 1 || width > 100'000 || height > 100'000) {
        return absl::InvalidArgumentError("PNG: width and height must be in [1, 100000]");
      }
      channels = colour == 0 ? 1 : 3;
    } else if (type == "IDAT") {
      idat += data;
    } else if (type == "IEND") {
      seen_end = true;
    }
    at += 12 + length;
  }
  if (channels == 0) return absl::InvalidArgumentError("PNG: no IHDR chunk");
  if (!seen_end) return absl::InvalidArgumentError("PNG: no IEND chunk");
  // Deflate compresses at most ~1032:1, so a small file cannot honestly claim a huge image.
  if (static_cast<uint64_t>(width) * height * channels > 1032 * static_cast<uint64_t>(idat.size()) + 1024) {
    return absl::InvalidArgumentError("PNG: IDAT is too small for the image's size");
  }

  const size_t row_bytes = static_cast<size_t>(width) * channels;
  uLongf raw_size = (row_bytes + 1) * height;
  std::string raw(raw_size, '\0');
  if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &raw_size, reinterpret_cast<const Bytef*>(idat.data()),
                 idat.size()) != Z_OK ||
      raw_size != raw.size()) {
    return absl::InvalidArgumentError("PNG: IDAT does not inflate to the image's size");
  }
  Image image(width, height, channels);
  for (int y = 0; y < height; ++y) {
    const auto* in = reinterpret_cast<const unsigned char*>(raw.data()) + y * (row_bytes + 1);
    const int filter = in[0];
    uint8_t* row = image.pixels.data() + y * row_bytes;
    const uint8_t* above = y > 0 ? row - row_bytes : nullptr;
    for (size_t i = 0; i < row_bytes; ++i) {
      const int a = i >= static_cast<size_t>(channels) ? row[i - channels] : 0;
      const int b = above != nullptr ? above[i] : 0;
      const int c = above != nullptr && i >= static_cast<size_t>(channels) ? above[i - channels] : 0;
      int predictor;
      switch (filter) {
        case 0: predictor = 0; break;
        case 1: predictor = a; break;
        case 2: predictor = b; break;
        case 3: predictor = (a + b) / 2; break;
        case 4: predictor = Paeth(a, b, c); break;
        default: return absl::InvalidArgumentError(absl::StrCat("PNG: unknown filter ", filter, " on row ", y));
      }
      row[i] = static_cast<uint8_t>(in[1 + i] + predictor);
    }
  }
  return image;
}

absl::StatusOr<Image> ReadPng(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open: ", std::strerror(errno)));
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  absl::StatusOr<Image> image = DecodePng(bytes);
  if (!image.ok()) return absl::Status(image.status().code(), absl::StrCat(path, ": ", image.status().message()));
  return image;
}

}  // namespace fremen::formats
