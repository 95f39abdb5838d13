#include "storage/shard_records.h"

#include <cstring>

#include "storage/model/varint.h"

namespace fremen::storage::shard_records {

std::string EncodeLabel(std::string_view name, std::string_view group) {
  std::string value;
  model::PutVarint64(&value, name.size());
  value += name;
  model::PutVarint64(&value, group.size());
  value += group;
  return value;
}

absl::StatusOr<std::pair<std::string, std::string>> DecodeLabel(std::string_view bytes) {
  model::ByteReader r(bytes, "labels");
  std::string name(r.Bytes(r.Varint("name length"), "name"));
  std::string group(r.Bytes(r.Varint("group length"), "group"));
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  return std::pair{std::move(name), std::move(group)};
}

absl::StatusOr<uint64_t> DecodeCheckpointLsn(std::span<const uint8_t> bytes) {
  if (bytes.size() != 8) return absl::DataLossError("shard meta: checkpoint_lsn is not 8 bytes");
  uint64_t lsn;
  std::memcpy(&lsn, bytes.data(), 8);
  return lsn;
}

std::string EncodeTouched(std::span<const uint64_t> sorted_keys) {
  std::string out;
  model::PutVarint64(&out, sorted_keys.size());
  uint64_t previous = 0;
  for (uint64_t key : sorted_keys) {
    model::PutVarint64(&out, key - previous);
    previous = key;
  }
  return out;
}

absl::StatusOr<std::vector<uint64_t>> DecodeTouched(std::string_view bytes) {
  model::ByteReader r(bytes, "touched states");
  const uint64_t count = r.Varint("count");
  if (r.ok() && count > r.remaining()) r.Fail("count", "more keys than bytes");  // each delta takes ≥ 1 byte
  std::vector<uint64_t> keys;
  uint64_t key = 0;
  for (uint64_t i = 0; i < count && r.ok(); ++i) {
    key += r.Varint("key delta");
    if (r.ok()) keys.push_back(key);
  }
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  return keys;
}

}  // namespace fremen::storage::shard_records
