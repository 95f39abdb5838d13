#include "server/services/map_tail.h"

#include <xxhash.h>

#include "absl/strings/str_cat.h"
#include "server/services/map_transfer.h"

namespace fremen::server {

namespace {

absl::Status Damaged(const std::string& what) {
  return absl::DataLossError(absl::StrCat("the map's tail is damaged: ", what, "; nothing of it was applied"));
}

}  // namespace

absl::Status ExportMapTail(storage::Store& store, const std::string& name, uint64_t after_lsn,
                           const std::function<bool(const v1::MapChunk&)>& send) {
  auto map = store.Map(name);
  if (!map.ok()) return map.status();
  auto tail = (*map)->Tail(after_lsn);
  if (!tail.ok()) return tail.status();
  const auto gone = [&] {
    return absl::CancelledError(absl::StrCat("tail of map ", name, ": the client went away"));
  };
  v1::MapChunk message;
  v1::MapExportHeader& header = *message.mutable_header();
  header.set_format(kMapExportFormat);
  header.set_kind(v1::MAP_EXPORT_KIND_TAIL);
  header.set_map(name);
  header.set_snapshot_lsn(after_lsn);
  if (!send(message)) return gone();
  uint64_t bytes = 0;
  for (const storage::TailRecord& r : *tail) {
    message.Clear();
    v1::MapTailBatch& batch = *message.mutable_batch();
    batch.set_lsn(r.lsn);
    batch.set_batch(r.batch);
    batch.set_xxh3(XXH3_64bits(r.batch.data(), r.batch.size()));
    if (!send(message)) return gone();
    bytes += r.batch.size();
  }
  message.Clear();
  message.mutable_trailer()->set_chunks(tail->size());
  message.mutable_trailer()->set_bytes(bytes);
  if (!send(message)) return gone();
  return absl::OkStatus();
}

absl::Status MapTailReader::Add(const v1::MapChunk& chunk) {
  if (trailer_) return Damaged("a message follows the trailer");
  if (!header_ && !chunk.has_header()) return Damaged("the stream does not start with a header");
  switch (chunk.part_case()) {
    case v1::MapChunk::kHeader:
      if (header_) return Damaged("a second header");
      if (chunk.header().format() != kMapExportFormat) {
        return absl::FailedPreconditionError(absl::StrCat("the stream's format is ", chunk.header().format(),
                                                          "; this fremend reads ", kMapExportFormat));
      }
      if (chunk.header().kind() != v1::MAP_EXPORT_KIND_TAIL) return Damaged("the header is not a tail's");
      header_ = chunk.header();
      return absl::OkStatus();
    case v1::MapChunk::kBatch: {
      const v1::MapTailBatch& batch = chunk.batch();
      const uint64_t n = records_.size() + 1;
      const uint64_t previous = records_.empty() ? header_->snapshot_lsn() : records_.back().lsn;
      if (batch.lsn() <= previous) {
        return Damaged(absl::StrCat("batch ", n, " is at LSN ", batch.lsn(), ", not after LSN ", previous));
      }
      if (XXH3_64bits(batch.batch().data(), batch.batch().size()) != batch.xxh3()) {
        return Damaged(absl::StrCat("batch ", n, " (LSN ", batch.lsn(), "): checksum mismatch"));
      }
      records_.push_back(storage::TailRecord{batch.lsn(), batch.batch()});
      bytes_ += batch.batch().size();
      return absl::OkStatus();
    }
    case v1::MapChunk::kTrailer:
      if (chunk.trailer().chunks() != records_.size() || chunk.trailer().bytes() != bytes_) {
        return Damaged(absl::StrCat("the trailer counts ", chunk.trailer().chunks(), " batches of ",
                                    chunk.trailer().bytes(), " bytes; the stream held ", records_.size(), " of ",
                                    bytes_));
      }
      trailer_ = true;
      return absl::OkStatus();
    case v1::MapChunk::kData:
      return Damaged("a snapshot's file data in a tail");
    case v1::MapChunk::PART_NOT_SET:
      break;
  }
  return Damaged("a message with neither header, batch nor trailer");
}

absl::Status MapTailReader::Finish() const {
  if (!header_) return Damaged("the stream is empty");
  if (!trailer_) return Damaged(absl::StrCat("the stream ended after ", records_.size(), " batches, before its trailer"));
  return absl::OkStatus();
}

absl::StatusOr<storage::MapInfo> ApplyMapTail(storage::Store& store, const std::string& name,
                                              const MapTailReader& reader) {
  auto map = store.Map(name);
  if (!map.ok()) return map.status();
  if ((*map)->Move().state != storage::MoveState::kIncoming) {
    return absl::FailedPreconditionError(absl::StrCat("map ", name, " is not a move's copy waiting for its tail"));
  }
  if (absl::Status applied = (*map)->ApplyTail(reader.header()->snapshot_lsn(), reader.records()); !applied.ok()) {
    return applied;
  }
  return (*map)->info();
}

void DropIncomingCopy(storage::Store& store, const std::string& name) {
  auto map = store.Map(name);
  if (!map.ok() || (*map)->Move().state != storage::MoveState::kIncoming) return;
  map->reset();
  (void)store.DeleteMap(name);
}

}  // namespace fremen::server
