// Byte coding of the model records: LEB128 varints, zigzag, little-endian fixed-width values, and a
// bounds-checked reader for decoding bytes that may be truncated or corrupted.
//
// Varints are canonical: the shortest encoding of a value is the only one accepted, so a decoded
// record re-encodes to the same bytes and a corrupted continuation bit cannot hide as a valid value.
// Thread-safety: free functions are pure; a ByteReader is a cursor owned by one decoder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fremen::model {

inline constexpr size_t kMaxVarint64Bytes = 10;

// Writes the LEB128 encoding of v (7 bits per byte, low bits first, high bit = more bytes follow)
// at dst, which must have room for kMaxVarint64Bytes; returns the end. Inline: encoders of long
// arrays (a scan's keys) call it per element into a buffer sized once.
inline char* EncodeVarint64(char* dst, uint64_t v) {
  while (v >= 0x80) {
    *dst++ = static_cast<char>(v | 0x80);
    v >>= 7;
  }
  *dst++ = static_cast<char>(v);
  return dst;
}
// Appends the LEB128 encoding of v.
void PutVarint64(std::string* out, uint64_t v);
// The encoded length of v in bytes (1..10).
size_t Varint64Length(uint64_t v);

// Zigzag maps signed to unsigned so that small magnitudes of either sign get short varints.
inline uint64_t ZigZagEncode64(int64_t v) {
  return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63);
}
inline int64_t ZigZagDecode64(uint64_t v) { return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1); }

// Little-endian fixed-width values at a position in raw bytes (REQUIRES: 4 or 8 bytes there), for
// formats framed outside a ByteReader: the log's record headers, the LMDB record checksum, the
// salvage child's frames.
inline void EncodeFixed32(void* dst, uint32_t v) {
  auto* p = static_cast<unsigned char*>(dst);
  for (size_t i = 0; i < 4; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline void EncodeFixed64(void* dst, uint64_t v) {
  auto* p = static_cast<unsigned char*>(dst);
  for (size_t i = 0; i < 8; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline uint32_t DecodeFixed32(const void* src) {
  const auto* p = static_cast<const unsigned char*>(src);
  uint32_t v = 0;
  for (size_t i = 0; i < 4; ++i) v |= uint32_t{p[i]} << (8 * i);
  return v;
}
inline uint64_t DecodeFixed64(const void* src) {
  const auto* p = static_cast<const unsigned char*>(src);
  uint64_t v = 0;
  for (size_t i = 0; i < 8; ++i) v |= uint64_t{p[i]} << (8 * i);
  return v;
}

// Appended little-endian fixed-width values; float and double by their IEEE-754 bit patterns.
void PutFixed32(std::string* out, uint32_t v);
void PutFixed64(std::string* out, uint64_t v);
void PutFloat(std::string* out, float v);
// PutFloat of every value, in one append on a little-endian machine.
void PutFloats(std::string* out, std::span<const float> values);
void PutDouble(std::string* out, double v);

// Reads a record front to back. Every read checks the remaining length first. The first failure is
// sticky: it is kept as a DataLoss status naming the record, the field and the byte offset, and every
// later read returns 0 without reading, so a decoder can read a group of fields and check ok() once
// before using them.
class ByteReader {
 public:
  // `record` names what is decoded in error messages, e.g. "lossless history".
  ByteReader(std::string_view bytes, std::string_view record) : bytes_(bytes), record_(record) {}

  // A varint: fails (DataLoss) on truncated, overlong (more than 64 bits) or non-canonical
  // (redundant trailing zero byte) input.
  uint64_t Varint(std::string_view field);
  uint8_t Byte(std::string_view field);
  uint32_t Fixed32(std::string_view field);
  uint64_t Fixed64(std::string_view field);
  float Float(std::string_view field);
  double Double(std::string_view field);
  // The next n bytes, as a view into the input.
  std::string_view Bytes(uint64_t n, std::string_view field);

  // Records a semantic error found by the decoder (e.g. a value out of range) at the current offset.
  // Keeps the first error only.
  void Fail(std::string_view field, std::string_view problem);

  bool ok() const { return status_.ok(); }
  const absl::Status& status() const { return status_; }
  size_t offset() const { return offset_; }
  size_t remaining() const { return bytes_.size() - offset_; }
  // The bytes read from `offset` up to the current offset.
  std::string_view Since(size_t offset) const { return bytes_.substr(offset, offset_ - offset); }
  // OK when everything was read without error; DataLoss when bytes are left over.
  absl::Status Finish();

 private:
  bool Need(size_t n, std::string_view field);

  std::string_view bytes_;
  std::string_view record_;
  size_t offset_ = 0;
  absl::Status status_;
};

}  // namespace fremen::model
