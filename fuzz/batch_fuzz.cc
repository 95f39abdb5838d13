// The write-ahead log's payload (storage/batch.h DecodeBatch, what recovery decodes for every
// logged record), then what recovery does with a decoded batch: ValidateBatch and Classify against
// the map. A payload that decodes re-encodes to a payload that decodes to the same bytes. Input: a
// byte choosing the map (fuzz_util.h FuzzMap), then the payload.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_map.h"
#include "fuzz/fuzz_util.h"
#include "storage/batch.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  if (size < 1) return 0;
  auto batch = storage::DecodeBatch(fuzz::AsView(data + 1, size - 1));
  if (!batch.ok()) {
    FUZZ_CHECK(absl::IsDataLoss(batch.status()), batch.status().ToString());
    return 0;
  }
  const std::string encoded = storage::EncodeBatch(*batch);
  auto again = storage::DecodeBatch(encoded);
  FUZZ_CHECK(again.ok(), again.status().ToString());
  FUZZ_CHECK(storage::EncodeBatch(*again) == encoded, "batch round trip");
  const storage::MapInfo map = fuzz::FuzzMap(data[0]);
  if (!storage::ValidateBatch(map, *batch).ok()) return 0;
  std::vector<uint8_t> accept;
  const storage::BatchAck ack = storage::Classify(map, *batch, accept);
  FUZZ_CHECK(ack.accepted + ack.rejected == batch->observation_count(), "every observation counted");
  return 0;
}
