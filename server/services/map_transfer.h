// A map as a stream of checksummed chunks (ExportMap, ImportMap; `fremenctl export`/`import` and
// moves between daemons, docs/fleet.md). The content is a backup (storage's Store::BackupMap: the
// map's info and each shard's LMDB file, compacted, at one checkpoint), so an import is a restore
// (Store::RestoreMap, which verifies every record before the map is listed) and there is one
// format of a map's copy, not two.
//
// The stream: a header (format, the map's name and encoded info, each file's path, size and
// XXH3-64), then each file's data in order in chunks of at most chunk_bytes, each with the XXH3-64
// of its bytes and its offset, then a trailer (chunks and bytes). MapImportWriter checks every
// chunk as it comes — its checksum, that it continues its file where the previous one stopped, that
// no file grows past its size, each whole file's checksum — and the trailer, so that a damaged or
// torn stream is DATA_LOSS before anything is created.
//
// Files are staged under <data_dir>/transfers: an export's backup copy while it is sent, an
// import's files until the restore. Both are removed when the call ends; ClearTransfers removes what
// a killed daemon left.
// Thread-compatible: one call uses one exporter or one writer.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fremen/v1/admin.pb.h"
#include "storage/map_info.h"
#include "storage/store.h"

namespace fremen::server {

inline constexpr uint32_t kMapExportFormat = 1;
inline constexpr uint32_t kDefaultChunkBytes = 1u << 20;
inline constexpr uint32_t kMaxChunkBytes = 4u << 20;

// <data_dir>/transfers.
std::string TransfersDir(const std::string& data_dir);
// Removes what a previous process left under TransfersDir (called once at start).
void ClearTransfers(const std::string& data_dir);

// A fresh, empty staging directory under TransfersDir: "<kind>-<n>" (made, with its parent).
absl::StatusOr<std::string> NewTransferDir(const std::string& data_dir, const std::string& kind);

// Sends map `name` of `store`: backs it up into a staging directory, then calls `send` with the
// header, every data chunk and the trailer, in order; stops at the first `send` that answers
// false (the client has gone: Cancelled). The staging copy is removed before returning.
// chunk_bytes 0 = kDefaultChunkBytes; larger than kMaxChunkBytes is InvalidArgument.
// kind ONLINE_SNAPSHOT first starts the map's tail (MapStore::StartTail), so that the batches
// logged after the snapshot can follow it (ExportMapTail, server/services/map_tail.h); the header
// gives the snapshot's LSN either way. TAIL is not this function's (InvalidArgument).
absl::Status ExportMap(storage::Store& store, const std::string& name, const std::string& data_dir,
                       uint32_t chunk_bytes, v1::MapExportKind kind,
                       const std::function<bool(const v1::MapChunk&)>& send);

// Receives one exported map into `dir` (an empty directory the caller made and removes), checking
// each message as it comes. Add the messages in order, then Finish.
class MapImportWriter {
 public:
  explicit MapImportWriter(std::string dir);
  ~MapImportWriter();

  // The first message must be the header, the last the trailer. DataLoss on a damaged, misplaced
  // or missing chunk; FailedPrecondition for a later format; InvalidArgument for a header whose
  // files are not a map's (paths other than its shards') or that is a tail's. An ONLINE_SNAPSHOT's
  // files include storage::kIncomingFile, so that the restored map waits for its tail.
  absl::Status Add(const v1::MapChunk& chunk);
  // Once the client's stream has ended: DataLoss unless the trailer came and matched (a torn stream).
  absl::Status Finish() const;

  // Set once the header is added.
  const std::optional<v1::MapExportHeader>& header() const { return header_; }
  const std::string& dir() const { return dir_; }
  uint64_t bytes() const { return bytes_; }

 private:
  absl::Status AddHeader(const v1::MapExportHeader& header);
  absl::Status AddData(const v1::MapFileChunk& data);
  absl::Status AddTrailer(const v1::MapExportTrailer& trailer);
  // Opens file `index` for writing (closing the previous one).
  absl::Status OpenFile(uint32_t index);
  // Closes the file being written, checking its size and whole checksum.
  absl::Status CloseFile();

  const std::string dir_;
  std::optional<v1::MapExportHeader> header_;
  bool trailer_ = false;
  std::optional<uint32_t> file_;  // the file being written
  uint32_t next_file_ = 0;        // files before it are complete
  uint64_t offset_ = 0;           // bytes of file_ written
  uint64_t chunks_ = 0, bytes_ = 0;
  struct Open;
  std::unique_ptr<Open> open_;  // the file being written and its running checksum
};

}  // namespace fremen::server
