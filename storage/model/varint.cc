#include "storage/model/varint.h"

#include <bit>

#include "absl/strings/str_cat.h"

namespace fremen::model {

namespace {

// Decodes one varint from p[0, size). Returns the bytes consumed, or 0 with *problem set.
size_t DecodeVarint(const unsigned char* p, size_t size, uint64_t* value, const char** problem) {
  uint64_t v = 0;
  for (size_t i = 0; i < kMaxVarint64Bytes; ++i) {
    if (i == size) {
      *problem = "truncated varint";
      return 0;
    }
    const unsigned char b = p[i];
    // The 10th byte holds only bit 63: anything more does not fit in 64 bits.
    if (i == kMaxVarint64Bytes - 1 && b > 1) {
      *problem = "overlong varint (more than 64 bits)";
      return 0;
    }
    v |= static_cast<uint64_t>(b & 0x7f) << (7 * i);
    if ((b & 0x80) == 0) {
      if (i > 0 && b == 0) {
        *problem = "non-canonical varint (redundant zero byte)";
        return 0;
      }
      *value = v;
      return i + 1;
    }
  }
  *problem = "overlong varint (more than 64 bits)";  // unreachable: the 10th byte check returns first
  return 0;
}

}  // namespace

void PutVarint64(std::string* out, uint64_t v) {
  char buf[kMaxVarint64Bytes];
  out->append(buf, EncodeVarint64(buf, v) - buf);
}

size_t Varint64Length(uint64_t v) {
  // 7 payload bits per byte; 0 still takes one byte.
  const int bits = std::bit_width(v | 1);
  return static_cast<size_t>((bits + 6) / 7);
}

void PutFixed32(std::string* out, uint32_t v) {
  char bytes[4];
  EncodeFixed32(bytes, v);
  out->append(bytes, sizeof(bytes));
}
void PutFixed64(std::string* out, uint64_t v) {
  char bytes[8];
  EncodeFixed64(bytes, v);
  out->append(bytes, sizeof(bytes));
}
void PutFloat(std::string* out, float v) { PutFixed32(out, std::bit_cast<uint32_t>(v)); }
void PutFloats(std::string* out, std::span<const float> values) {
  if constexpr (std::endian::native == std::endian::little) {
    out->append(reinterpret_cast<const char*>(values.data()), values.size_bytes());
  } else {
    for (const float v : values) PutFloat(out, v);
  }
}
void PutDouble(std::string* out, double v) { PutFixed64(out, std::bit_cast<uint64_t>(v)); }

bool ByteReader::Need(size_t n, std::string_view field) {
  if (!ok()) return false;
  if (n > remaining()) {
    Fail(field, absl::StrCat("truncated: needs ", n, " bytes, ", remaining(), " left"));
    return false;
  }
  return true;
}

void ByteReader::Fail(std::string_view field, std::string_view problem) {
  if (!ok()) return;
  // std::string_view is not absl::string_view in this abseil build: StrCat cannot take the views.
  std::string message(record_);
  message.append(": ").append(field).append(": ").append(problem);
  status_ = absl::DataLossError(absl::StrCat(message, " (at byte ", offset_, ")"));
}

uint64_t ByteReader::Varint(std::string_view field) {
  if (!ok()) return 0;
  uint64_t v = 0;
  const char* problem = nullptr;
  const size_t n =
      DecodeVarint(reinterpret_cast<const unsigned char*>(bytes_.data() + offset_), remaining(), &v, &problem);
  if (n == 0) {
    Fail(field, problem);
    return 0;
  }
  offset_ += n;
  return v;
}

uint8_t ByteReader::Byte(std::string_view field) {
  if (!Need(1, field)) return 0;
  return static_cast<uint8_t>(bytes_[offset_++]);
}

uint32_t ByteReader::Fixed32(std::string_view field) {
  if (!Need(4, field)) return 0;
  const uint32_t v = DecodeFixed32(bytes_.data() + offset_);
  offset_ += 4;
  return v;
}

uint64_t ByteReader::Fixed64(std::string_view field) {
  if (!Need(8, field)) return 0;
  const uint64_t v = DecodeFixed64(bytes_.data() + offset_);
  offset_ += 8;
  return v;
}

float ByteReader::Float(std::string_view field) { return std::bit_cast<float>(Fixed32(field)); }
double ByteReader::Double(std::string_view field) { return std::bit_cast<double>(Fixed64(field)); }

std::string_view ByteReader::Bytes(uint64_t n, std::string_view field) {
  if (!Need(n, field)) return {};
  const std::string_view v = bytes_.substr(offset_, n);
  offset_ += n;
  return v;
}

absl::Status ByteReader::Finish() {
  if (ok() && remaining() > 0) Fail("end", absl::StrCat(remaining(), " unexpected trailing bytes"));
  return status_;
}

}  // namespace fremen::model
