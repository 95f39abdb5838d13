// An online move's tail as a stream: the batches a map logged after its ONLINE_SNAPSHOT export,
// sent once its writes are stopped (ExportMap kind TAIL) and applied to the incoming copy on the
// new owner (ImportMap of that stream; docs/fleet.md, "The protocol").
//
// The stream: a header (format, kind TAIL, the map, the snapshot's LSN the batches follow), one
// MapTailBatch per batch (its LSN in the source's log, its encoded bytes, their XXH3-64), then a
// trailer (batches and bytes). MapTailReader checks every message as it comes — the checksum, that
// LSNs increase after the snapshot's — and the trailer, so that a damaged or torn tail is DATA_LOSS
// before any of it is applied.
// Thread-compatible.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fremen/v1/admin.pb.h"
#include "storage/map_store.h"
#include "storage/store.h"

namespace fremen::server {

// Sends the tail of map `name` after `after_lsn` (MapStore::Tail) with `send`; stops at the first
// `send` that answers false (Cancelled).
absl::Status ExportMapTail(storage::Store& store, const std::string& name, uint64_t after_lsn,
                           const std::function<bool(const v1::MapChunk&)>& send);

// Receives a tail. Add the messages in order, then Finish.
class MapTailReader {
 public:
  // DataLoss on a damaged, misplaced or missing message; FailedPrecondition for a later format.
  absl::Status Add(const v1::MapChunk& chunk);
  // Once the stream has ended: DataLoss unless the trailer came and matched.
  absl::Status Finish() const;

  const std::optional<v1::MapExportHeader>& header() const { return header_; }
  const std::vector<storage::TailRecord>& records() const { return records_; }
  uint64_t bytes() const { return bytes_; }

 private:
  std::optional<v1::MapExportHeader> header_;
  bool trailer_ = false;
  std::vector<storage::TailRecord> records_;
  uint64_t bytes_ = 0;
};

// Applies a finished reader's tail to the incoming copy `name` (its header's map, resolved by the
// caller) and serves it (MapStore::ApplyTail). FailedPrecondition for a map that is not incoming.
absl::StatusOr<storage::MapInfo> ApplyMapTail(storage::Store& store, const std::string& name,
                                              const MapTailReader& reader);

// Deletes `name` if it is an incoming copy: what a tail import that failed leaves (a damaged
// tail, one that does not continue the snapshot, a client gone), so that no half-moved map is
// left to be served; the move is made again from a new snapshot. A map that is not incoming
// (serving, or absent) is left alone.
void DropIncomingCopy(storage::Store& store, const std::string& name);

}  // namespace fremen::server
