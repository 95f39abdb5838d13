#include "tests/store_writer.h"

#include <condition_variable>
#include <future>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "storage/store.h"

namespace fremen::testing {

absl::Status WriteBatches(const std::string& data_dir, const std::string& map,
                          std::vector<storage::ObservationBatch> batches) {
  auto store = storage::Store::Open(data_dir, storage::StoreOptions());
  if (!store.ok()) return store.status();
  auto opened = (*store)->Map(map);
  if (!opened.ok()) return opened.status();
  std::mutex mutex;
  std::condition_variable acked;
  size_t pending = 0;
  absl::Status first_error;
  const auto done = [&](absl::StatusOr<storage::BatchAck> ack) {
    std::lock_guard lock(mutex);
    if (!ack.ok() && first_error.ok()) first_error = ack.status();
    if (ack.ok() && ack->rejected > 0 && first_error.ok()) {
      first_error = absl::InvalidArgumentError(absl::StrCat("batch ", ack->sequence, ": ", ack->rejected, " rejected"));
    }
    --pending;
    acked.notify_all();
  };
  // The writer id is new in every call, so that batches of an earlier call are not taken for retries.
  static uint64_t writer = 1000;
  ++writer;
  uint64_t sequence = 0;
  for (storage::ObservationBatch& batch : batches) {
    batch.writer_id = writer;
    batch.sequence = ++sequence;
    {
      std::lock_guard lock(mutex);
      ++pending;
    }
    absl::Status submitted = (*opened)->Submit(batch, done);
    while (absl::IsResourceExhausted(submitted)) {  // backpressure: wait for room
      std::promise<void> room;
      (*opened)->OnRoom(batch.observation_count(), [&room] { room.set_value(); });
      room.get_future().wait();
      submitted = (*opened)->Submit(batch, done);
    }
    if (!submitted.ok()) return submitted;
  }
  std::unique_lock lock(mutex);
  acked.wait(lock, [&] { return pending == 0; });
  lock.unlock();
  if (!first_error.ok()) return first_error;
  return (*store)->Close();
}

storage::ObservationBatch GenericScan(const std::vector<uint64_t>& ids, const std::vector<float>& values, double t) {
  storage::ObservationBatch batch;
  batch.time = t;
  batch.keys.assign(ids.begin(), ids.end());
  batch.values.assign(values.begin(), values.end());
  return batch;
}

storage::ObservationBatch GridScan(uint32_t nx, uint32_t ny, double t, float value) {
  storage::ObservationBatch batch;
  batch.time = t;
  batch.patch.size = {nx, ny, 1};
  batch.patch.values.assign(size_t{nx} * ny, value);
  return batch;
}

}  // namespace fremen::testing
