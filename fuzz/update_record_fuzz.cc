// A map's last update record (storage/update_record.h DecodeUpdateRecord, read from <map
// dir>/last_update at open). A record that decodes re-encodes to one that decodes the same. Input:
// the file's bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_util.h"
#include "storage/update_record.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  auto record = storage::DecodeUpdateRecord(fuzz::AsView(data, size));
  if (!record.ok()) {
    FUZZ_CHECK(absl::IsDataLoss(record.status()), record.status().ToString());
    return 0;
  }
  const std::string encoded = storage::EncodeUpdateRecord(*record);
  auto again = storage::DecodeUpdateRecord(encoded);
  FUZZ_CHECK(again.ok(), again.status().ToString());
  FUZZ_CHECK(storage::EncodeUpdateRecord(*again) == encoded, "update record round trip");
  return 0;
}
