#include "storage/dedup_table.h"

#include "storage/model/varint.h"

namespace fremen::storage {

// Layout: writer count varint, then (writer varint, sequence varint) pairs.
std::string DedupTable::Encode() const {
  std::string out;
  model::PutVarint64(&out, last_.size());
  for (const auto& [writer, sequence] : last_) {
    model::PutVarint64(&out, writer);
    model::PutVarint64(&out, sequence);
  }
  return out;
}

absl::StatusOr<DedupTable> DedupTable::Decode(std::string_view bytes) {
  model::ByteReader r(bytes, "dedup table");
  DedupTable table;
  const uint64_t count = r.Varint("writer count");
  if (r.ok() && count * 2 > r.remaining()) r.Fail("writer count", "more than the bytes left");
  for (uint64_t i = 0; r.ok() && i < count; ++i) {
    const uint64_t writer = r.Varint("writer");
    table.Record(writer, r.Varint("sequence"));
  }
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  return table;
}

}  // namespace fremen::storage
