// IngestRequest → ObservationBatch (server/convert/ingest_convert.h), then what the store does with an
// accepted batch before it is logged: ValidateBatch, Classify and the log payload's round trip.
// Input: a byte choosing the map (fuzz_util.h FuzzMap), then a serialized fremen.v1.IngestRequest.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fremen/v1/ingest.pb.h"
#include "fuzz/fuzz_map.h"
#include "fuzz/fuzz_util.h"
#include "server/convert/ingest_convert.h"
#include "storage/batch.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  if (size < 1) return 0;
  const storage::MapInfo map = fuzz::FuzzMap(data[0]);
  v1::IngestRequest request;
  if (!request.ParseFromArray(data + 1, static_cast<int>(size - 1))) return 0;
  auto batch = server::BatchFromRequest(map, request);
  if (!batch.ok()) {
    FUZZ_CHECK(absl::IsInvalidArgument(batch.status()), batch.status().ToString());
    v1::IngestResponse response;
    server::ErrorToResponse(request.sequence(), batch.status(), response);
    return 0;
  }
  if (!storage::ValidateBatch(map, *batch).ok()) return 0;
  std::vector<uint8_t> accept;
  const storage::BatchAck ack = storage::Classify(map, *batch, accept);
  FUZZ_CHECK(accept.size() == batch->observation_count(), "one verdict per observation");
  FUZZ_CHECK(ack.accepted + ack.rejected == batch->observation_count(), "every observation counted");
  v1::IngestResponse response;
  server::AckToResponse(ack, response);
  const std::string logged = storage::EncodeBatch(*batch);
  auto replayed = storage::DecodeBatch(logged);
  FUZZ_CHECK(replayed.ok(), replayed.status().ToString());
  FUZZ_CHECK(storage::EncodeBatch(*replayed) == logged, "the log payload round-trips");
  return 0;
}
