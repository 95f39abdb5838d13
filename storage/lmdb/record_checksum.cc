#include "storage/lmdb/record_checksum.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {

uint32_t Crc(uLong crc, std::span<const uint8_t> bytes) {
  // zlib takes uInt lengths: feed values past 4 GiB in pieces (LMDB values can be that large).
  while (!bytes.empty()) {
    const size_t n = std::min<size_t>(bytes.size(), 1u << 30);
    crc = crc32(crc, bytes.data(), static_cast<uInt>(n));
    bytes = bytes.subspan(n);
  }
  return static_cast<uint32_t>(crc);
}

}  // namespace

uint32_t RecordChecksum(std::span<const uint8_t> key, std::span<const uint8_t> value) {
  return Crc(Crc(crc32(0L, Z_NULL, 0), key), value);
}

static_assert(kRecordChecksumBytes == 4, "the checksum is stored as a little-endian fixed32");

void EncodeChecked(std::span<const uint8_t> key, std::span<const uint8_t> value, uint8_t* out) {
  if (!value.empty()) std::memcpy(out, value.data(), value.size());
  const uint32_t crc = RecordChecksum(key, value);
  model::EncodeFixed32(out + value.size(), crc);
}

absl::StatusOr<std::span<const uint8_t>> CheckRecord(std::span<const uint8_t> key, std::span<const uint8_t> stored) {
  if (stored.size() < kRecordChecksumBytes) {
    return absl::DataLossError(absl::StrCat("record of ", stored.size(), " bytes is shorter than its ",
                                            kRecordChecksumBytes, "-byte checksum"));
  }
  const std::span<const uint8_t> value = stored.first(stored.size() - kRecordChecksumBytes);
  const uint32_t expected = model::DecodeFixed32(stored.data() + value.size());
  if (const uint32_t actual = RecordChecksum(key, value); actual != expected) {
    return absl::DataLossError(absl::StrCat("checksum mismatch (stored ", absl::Hex(expected, absl::kZeroPad8),
                                            ", computed ", absl::Hex(actual, absl::kZeroPad8), ")"));
  }
  return value;
}

}  // namespace fremen::storage
