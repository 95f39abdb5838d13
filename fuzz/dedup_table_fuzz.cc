// A shard's checkpointed dedup table (storage/dedup_table.h DedupTable::Decode, read by
// Shard::Load). A table that decodes re-encodes to one that decodes to the same table. Input: the
// record's bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_util.h"
#include "storage/dedup_table.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  auto table = storage::DedupTable::Decode(fuzz::AsView(data, size));
  if (!table.ok()) {
    FUZZ_CHECK(absl::IsDataLoss(table.status()), table.status().ToString());
    return 0;
  }
  auto again = storage::DedupTable::Decode(table->Encode());
  FUZZ_CHECK(again.ok(), again.status().ToString());
  FUZZ_CHECK(*again == *table, "dedup table round trip");
  return 0;
}
