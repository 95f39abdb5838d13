// What a store tells an observer about its writes, for the daemon's metrics (server/metrics/), so
// that storage itself depends on no metrics library.
//
// The store asks StoreObserver::ForMap once for each map it opens (at Open, CreateMap, RestoreMap,
// SalvageMap) and calls that map's observer from its own threads: the committer (batches, log
// syncs), the checkpoint writer and the opening thread (recovery). Calls are per batch, per group
// commit or per checkpoint — never per observation — and must be quick: an implementation counts
// (relaxed atomics, a histogram's bucket) and returns; it must not call back into the store.
//
// Thread-safety: a MapObserver's methods may be called from several threads at once.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "absl/time/time.h"
#include "storage/batch.h"

namespace fremen::storage {

class MapObserver {
 public:
  virtual ~MapObserver() = default;
  // A batch answered by the committer with `ack` (durable and applied; a duplicate, or refused as a
  // whole when ack.error is set).
  virtual void BatchAnswered(const BatchAck& ack) = 0;
  // One group commit: `records` appended to the log, then written and fdatasynced in `took`.
  virtual void LogSynced(uint64_t records, absl::Duration took) = 0;
  // A checkpoint wrote `bytes` of records into the shards' LMDB files in `took` (failed ones are
  // not reported: the map then refuses writes, which its WriteError says).
  virtual void Checkpointed(uint64_t bytes, absl::Duration took) = 0;
  // The map was recovered (checkpoints loaded, log replayed) in `took`.
  virtual void Recovered(absl::Duration took) = 0;
};

class StoreObserver {
 public:
  virtual ~StoreObserver() = default;
  // The observer of the map named `map`, kept by the map until it closes. Called again for a map
  // opened anew under the same name (deleted and created, restored).
  virtual std::shared_ptr<MapObserver> ForMap(const std::string& map) = 0;
};

}  // namespace fremen::storage
