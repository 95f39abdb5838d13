// PGM reading and writing (see pgm.h).
#include "client/formats/pgm.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace fremen::formats {

namespace {

// Reads the whitespace-separated tokens of a Netpbm header (where '#' starts a comment to the end
// of the line) and, for P2, the pixel values.
class TokenReader {
 public:
  // Reads from `start` on (after the magic number).
  TokenReader(const std::string& bytes, size_t start) : bytes_(bytes), pos_(start) {}

  // The next unsigned integer; false at the end or on a non-digit.
  bool NextNumber(long& value) {
    SkipBlanksAndComments();
    if (pos_ >= bytes_.size() || !std::isdigit(static_cast<unsigned char>(bytes_[pos_]))) return false;
    value = 0;
    while (pos_ < bytes_.size() && std::isdigit(static_cast<unsigned char>(bytes_[pos_]))) {
      value = value * 10 + (bytes_[pos_++] - '0');
      if (value > 1'000'000'000) return false;
    }
    return true;
  }
  // After the header's last number exactly one whitespace byte precedes binary data.
  bool SkipOneWhitespace() {
    if (pos_ >= bytes_.size() || !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) return false;
    ++pos_;
    return true;
  }
  size_t pos() const { return pos_; }

 private:
  void SkipBlanksAndComments() {
    while (pos_ < bytes_.size()) {
      if (std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
        ++pos_;
      } else if (bytes_[pos_] == '#') {
        while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }

  const std::string& bytes_;
  size_t pos_;
};

uint8_t Rescale(long value, long maxval) {
  return static_cast<uint8_t>(maxval == 255 ? value : (value * 255 + maxval / 2) / maxval);
}

}  // namespace

absl::StatusOr<Image> ParsePgm(const std::string& bytes, const std::string& name) {
  if (bytes.size() < 2 || bytes[0] != 'P' || (bytes[1] != '5' && bytes[1] != '2')) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": not a PGM file (the magic number must be P5 or P2)"));
  }
  const bool binary = bytes[1] == '5';
  TokenReader header(bytes, 2);
  long width, height, maxval;
  if (!header.NextNumber(width) || width < 1 || width > 100'000) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": bad PGM header: width must be in [1, 100000]"));
  }
  if (!header.NextNumber(height) || height < 1 || height > 100'000) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": bad PGM header: height must be in [1, 100000]"));
  }
  if (!header.NextNumber(maxval) || maxval < 1 || maxval > 65535) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": bad PGM header: maxval must be in [1, 65535]"));
  }
  // The data must be there before the image is allocated: a corrupt header cannot ask for 10 GB.
  const size_t count = static_cast<size_t>(width) * height;
  const size_t min_data_bytes = binary ? count : 2 * count - 1;  // P2: a digit and a blank per value
  if (bytes.size() < min_data_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": truncated PGM data: a ", width, "x", height,
                                                   " image needs at least ", min_data_bytes, " bytes of pixels"));
  }
  Image image(static_cast<int>(width), static_cast<int>(height), 1);
  if (binary) {
    if (!header.SkipOneWhitespace()) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": bad PGM header: no whitespace after maxval"));
    }
    const size_t bytes_per_value = maxval < 256 ? 1 : 2;
    const size_t begin = header.pos();
    if (bytes.size() - begin < count * bytes_per_value) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": truncated PGM data: expected ", count * bytes_per_value,
                                                     " bytes of pixels, found ", bytes.size() - begin));
    }
    for (size_t i = 0; i < count; ++i) {
      const unsigned char* p = reinterpret_cast<const unsigned char*>(bytes.data() + begin + i * bytes_per_value);
      // 16-bit samples are big-endian (Netpbm).
      const long value = bytes_per_value == 1 ? p[0] : (p[0] << 8) | p[1];
      if (value > maxval) {
        return absl::InvalidArgumentError(absl::StrCat(name, ": pixel ", i, " is ", value, ", above maxval ", maxval));
      }
      image.pixels[i] = Rescale(value, maxval);
    }
  } else {
    for (size_t i = 0; i < count; ++i) {
      long value;
      if (!header.NextNumber(value)) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": truncated or malformed P2 data: expected ", count, " pixel values, read ", i));
      }
      if (value > maxval) {
        return absl::InvalidArgumentError(absl::StrCat(name, ": pixel ", i, " is ", value, ", above maxval ", maxval));
      }
      image.pixels[i] = Rescale(value, maxval);
    }
  }
  return image;
}

absl::StatusOr<Image> ReadPgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open: ", std::strerror(errno)));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return absl::DataLossError(absl::StrCat(path, ": read error"));
  return ParsePgm(bytes, path);
}

absl::Status WritePgm(const std::string& path, const Image& image) {
  if (image.channels != 1) return absl::InvalidArgumentError("WritePgm: the image must have one channel");
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return absl::PermissionDeniedError(absl::StrCat(path, ": cannot create: ", std::strerror(errno)));
  out << "P5\n" << image.width << ' ' << image.height << "\n255\n";
  out.write(reinterpret_cast<const char*>(image.pixels.data()), static_cast<std::streamsize>(image.pixels.size()));
  out.close();
  if (!out) return absl::DataLossError(absl::StrCat(path, ": write error"));
  return absl::OkStatus();
}

}  // namespace fremen::formats
