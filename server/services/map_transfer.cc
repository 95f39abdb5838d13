#include "server/services/map_transfer.h"

#include <unistd.h>
#include <xxhash.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "absl/strings/str_cat.h"
#include "server/convert/map_convert.h"

namespace fremen::server {

namespace {

namespace fs = std::filesystem;

constexpr char kMapInfoFile[] = "map.info";
constexpr char kLastUpdateFile[] = "last_update";

absl::Status WriteWhole(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  out.close();
  if (!out) return absl::InternalError(absl::StrCat("cannot write ", path));
  return absl::OkStatus();
}

std::string ShardFile(uint32_t shard) { return absl::StrCat("shard-", shard, "/data.mdb"); }

absl::StatusOr<std::string> ReadWhole(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InternalError(absl::StrCat("cannot read ", path));
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// XXH3-64 of a file, read in pieces.
absl::StatusOr<uint64_t> FileChecksum(const std::string& path, std::vector<char>& buffer) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InternalError(absl::StrCat("cannot read ", path));
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    XXH3_64bits_update(state, buffer.data(), static_cast<size_t>(in.gcount()));
  }
  const uint64_t sum = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  if (in.bad()) return absl::InternalError(absl::StrCat("cannot read ", path));
  return sum;
}

// Removes a staging directory when the call ends, whatever way it ends.
class RemoveOnExit {
 public:
  explicit RemoveOnExit(std::string dir) : dir_(std::move(dir)) {}
  ~RemoveOnExit() {
    std::error_code error;
    fs::remove_all(dir_, error);
  }

 private:
  std::string dir_;
};

absl::Status Damaged(const std::string& what) {
  return absl::DataLossError(absl::StrCat("the map's stream is damaged: ", what, "; nothing was imported"));
}

}  // namespace

std::string TransfersDir(const std::string& data_dir) { return data_dir + "/transfers"; }

void ClearTransfers(const std::string& data_dir) {
  std::error_code error;
  fs::remove_all(TransfersDir(data_dir), error);
}

absl::StatusOr<std::string> NewTransferDir(const std::string& data_dir, const std::string& kind) {
  static std::atomic<uint64_t> next{0};
  const std::string root = TransfersDir(data_dir);
  std::error_code error;
  fs::create_directories(root, error);
  if (error) return absl::InternalError(absl::StrCat("cannot create ", root, ": ", error.message()));
  for (;;) {
    const std::string dir = absl::StrCat(root, "/", kind, "-", getpid(), "-", next++);
    if (fs::create_directory(dir, error)) return dir;
    if (error) return absl::InternalError(absl::StrCat("cannot create ", dir, ": ", error.message()));
  }
}

absl::Status ExportMap(storage::Store& store, const std::string& name, const std::string& data_dir,
                       uint32_t chunk_bytes, v1::MapExportKind kind,
                       const std::function<bool(const v1::MapChunk&)>& send) {
  if (kind != v1::MAP_EXPORT_KIND_SNAPSHOT && kind != v1::MAP_EXPORT_KIND_ONLINE_SNAPSHOT) {
    return absl::InvalidArgumentError(
        absl::StrCat("kind: must be SNAPSHOT or ONLINE_SNAPSHOT here, got ", v1::MapExportKind_Name(kind)));
  }
  if (chunk_bytes > kMaxChunkBytes) {
    return absl::InvalidArgumentError(absl::StrCat("chunk_bytes must be at most ", kMaxChunkBytes, ", got ", chunk_bytes));
  }
  if (chunk_bytes == 0) chunk_bytes = kDefaultChunkBytes;
  auto info = store.GetMap(name);
  if (!info.ok()) return info.status();
  auto staging = NewTransferDir(data_dir, "export");
  if (!staging.ok()) return staging.status();
  const RemoveOnExit cleanup(*staging);
  // BackupMap makes the directory itself.
  const std::string dir = *staging + "/map";
  if (kind == v1::MAP_EXPORT_KIND_ONLINE_SNAPSHOT) {
    // Before the snapshot's checkpoint: every batch logged after it is then recorded.
    auto map = store.Map(name);
    if (!map.ok()) return map.status();
    if (absl::Status started = (*map)->StartTail(); !started.ok()) return started;
  }
  uint64_t snapshot_lsn = 0;
  if (auto copied = store.BackupMap(name, dir, &snapshot_lsn); !copied.ok()) return copied.status();

  v1::MapChunk message;
  v1::MapExportHeader& header = *message.mutable_header();
  header.set_format(kMapExportFormat);
  header.set_map(name);
  header.set_kind(kind);
  header.set_snapshot_lsn(snapshot_lsn);
  MapInfoToProto(*info, *header.mutable_info());
  auto encoded = ReadWhole(absl::StrCat(dir, "/", kMapInfoFile));
  if (!encoded.ok()) return encoded.status();
  header.set_map_info(*std::move(encoded));
  if (fs::exists(absl::StrCat(dir, "/", kLastUpdateFile))) {
    auto last = ReadWhole(absl::StrCat(dir, "/", kLastUpdateFile));
    if (!last.ok()) return last.status();
    header.set_last_update(*std::move(last));
  }
  std::vector<char> buffer(chunk_bytes);
  for (uint32_t i = 0; i < info->shards; ++i) {
    const std::string path = absl::StrCat(dir, "/", ShardFile(i));
    std::error_code error;
    const uint64_t size = fs::file_size(path, error);
    if (error) return absl::InternalError(absl::StrCat("export of map ", name, ": ", path, ": ", error.message()));
    auto sum = FileChecksum(path, buffer);
    if (!sum.ok()) return sum.status();
    v1::MapExportFile& file = *header.add_files();
    file.set_path(ShardFile(i));
    file.set_bytes(size);
    file.set_xxh3(*sum);
  }
  const v1::MapExportHeader files = header;
  const auto gone = [&] {
    return absl::CancelledError(absl::StrCat("export of map ", name, ": the client went away"));
  };
  if (!send(message)) return gone();

  uint64_t chunks = 0, bytes = 0;
  for (int f = 0; f < files.files_size(); ++f) {
    std::ifstream in(absl::StrCat(dir, "/", files.files(f).path()), std::ios::binary);
    if (!in) return absl::InternalError(absl::StrCat("export of map ", name, ": cannot read ", files.files(f).path()));
    uint64_t offset = 0;
    while (offset < files.files(f).bytes()) {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      const size_t n = static_cast<size_t>(in.gcount());
      if (n == 0) return absl::InternalError(absl::StrCat("export of map ", name, ": ", files.files(f).path(), " shrank"));
      message.Clear();
      v1::MapFileChunk& data = *message.mutable_data();
      data.set_file(static_cast<uint32_t>(f));
      data.set_offset(offset);
      data.set_data(buffer.data(), n);
      data.set_xxh3(XXH3_64bits(buffer.data(), n));
      if (!send(message)) return gone();
      offset += n;
      bytes += n;
      ++chunks;
    }
  }
  message.Clear();
  message.mutable_trailer()->set_chunks(chunks);
  message.mutable_trailer()->set_bytes(bytes);
  if (!send(message)) return gone();
  return absl::OkStatus();
}

struct MapImportWriter::Open {
  std::ofstream out;
  XXH3_state_t* state = XXH3_createState();
  ~Open() { XXH3_freeState(state); }
};

MapImportWriter::MapImportWriter(std::string dir) : dir_(std::move(dir)) {}
MapImportWriter::~MapImportWriter() = default;

absl::Status MapImportWriter::Add(const v1::MapChunk& chunk) {
  if (trailer_) return Damaged("a message follows the trailer");
  if (!header_ && !chunk.has_header()) return Damaged("the stream does not start with a header");
  switch (chunk.part_case()) {
    case v1::MapChunk::kHeader:
      if (header_) return Damaged("a second header");
      return AddHeader(chunk.header());
    case v1::MapChunk::kData:
      return AddData(chunk.data());
    case v1::MapChunk::kTrailer:
      return AddTrailer(chunk.trailer());
    case v1::MapChunk::kBatch:
      return Damaged("a tail's batch in a map's snapshot");
    case v1::MapChunk::PART_NOT_SET:
      break;
  }
  return Damaged("a message with neither header, data nor trailer");
}

absl::Status MapImportWriter::AddHeader(const v1::MapExportHeader& header) {
  if (header.format() != kMapExportFormat) {
    return absl::FailedPreconditionError(absl::StrCat("the stream's format is ", header.format(), "; this fremend reads ",
                                                      kMapExportFormat, " (import it with a newer fremend)"));
  }
  if (header.kind() == v1::MAP_EXPORT_KIND_TAIL) {
    return absl::InvalidArgumentError("header.kind: a tail is not a map's snapshot");
  }
  auto info = storage::DecodeMapInfo(header.map_info());
  if (!info.ok()) return Damaged(absl::StrCat("header.map_info: ", info.status().message()));
  if (header.files_size() != static_cast<int>(info->shards)) {
    return absl::InvalidArgumentError(absl::StrCat("header: ", header.files_size(), " files for a map of ", info->shards,
                                                   " shards"));
  }
  for (int i = 0; i < header.files_size(); ++i) {
    if (header.files(i).path() != ShardFile(static_cast<uint32_t>(i))) {
      return absl::InvalidArgumentError(absl::StrCat("header.files[", i, "].path must be \"",
                                                     ShardFile(static_cast<uint32_t>(i)), "\", got \"",
                                                     header.files(i).path(), "\""));
    }
  }
  if (absl::Status s = WriteWhole(absl::StrCat(dir_, "/", kMapInfoFile), header.map_info()); !s.ok()) return s;
  if (!header.last_update().empty()) {
    if (absl::Status s = WriteWhole(absl::StrCat(dir_, "/", kLastUpdateFile), header.last_update()); !s.ok()) return s;
  }
  if (header.kind() == v1::MAP_EXPORT_KIND_ONLINE_SNAPSHOT) {
    const std::string marker = absl::StrCat(dir_, "/", storage::kIncomingFile);
    if (absl::Status s = WriteWhole(marker, absl::StrCat(header.snapshot_lsn())); !s.ok()) return s;
  }
  header_ = header;
  return absl::OkStatus();
}

absl::Status MapImportWriter::OpenFile(uint32_t index) {
  if (absl::Status closed = CloseFile(); !closed.ok()) return closed;
  const std::string path = absl::StrCat(dir_, "/", header_->files(index).path());
  std::error_code error;
  fs::create_directories(fs::path(path).parent_path(), error);
  if (error) return absl::InternalError(absl::StrCat("cannot create ", fs::path(path).parent_path().string()));
  open_ = std::make_unique<Open>();
  open_->out.open(path, std::ios::binary);
  if (!open_->out) return absl::InternalError(absl::StrCat("cannot write ", path));
  XXH3_64bits_reset(open_->state);
  file_ = index;
  offset_ = 0;
  return absl::OkStatus();
}

absl::Status MapImportWriter::CloseFile() {
  if (!file_) return absl::OkStatus();
  const v1::MapExportFile& file = header_->files(*file_);
  if (offset_ != file.bytes()) {
    return Damaged(absl::StrCat(file.path(), " ends at byte ", offset_, " of ", file.bytes()));
  }
  open_->out.close();
  if (!open_->out) return absl::InternalError(absl::StrCat("cannot write ", dir_, "/", file.path()));
  if (XXH3_64bits_digest(open_->state) != file.xxh3()) return Damaged(absl::StrCat(file.path(), ": checksum mismatch"));
  open_.reset();
  file_.reset();
  ++next_file_;
  return absl::OkStatus();
}

absl::Status MapImportWriter::AddData(const v1::MapFileChunk& data) {
  const uint64_t chunk = chunks_ + 1;
  if (data.file() >= static_cast<uint32_t>(header_->files_size())) {
    return Damaged(absl::StrCat("chunk ", chunk, " names file ", data.file(), " of ", header_->files_size()));
  }
  // A file's chunks come together and in order: a chunk of the next file closes this one.
  if (!file_ || data.file() != *file_) {
    const uint32_t expected = file_ ? *file_ + 1 : next_file_;
    if (data.file() != expected) {
      return Damaged(absl::StrCat("chunk ", chunk, " is of file ", data.file(), " where file ", expected, " was due"));
    }
    if (absl::Status opened = OpenFile(data.file()); !opened.ok()) return opened;
  }
  const v1::MapExportFile& file = header_->files(*file_);
  if (data.offset() != offset_) {
    return Damaged(absl::StrCat("chunk ", chunk, " of ", file.path(), " starts at byte ", data.offset(),
                                " where byte ", offset_, " was due (a chunk is missing or repeated)"));
  }
  if (offset_ + data.data().size() > file.bytes()) {
    return Damaged(absl::StrCat("chunk ", chunk, " goes past the ", file.bytes(), " bytes of ", file.path()));
  }
  if (XXH3_64bits(data.data().data(), data.data().size()) != data.xxh3()) {
    return Damaged(absl::StrCat("chunk ", chunk, " (", file.path(), " byte ", data.offset(), "): checksum mismatch"));
  }
  open_->out.write(data.data().data(), static_cast<std::streamsize>(data.data().size()));
  if (!open_->out) return absl::InternalError(absl::StrCat("cannot write ", dir_, "/", file.path()));
  XXH3_64bits_update(open_->state, data.data().data(), data.data().size());
  offset_ += data.data().size();
  bytes_ += data.data().size();
  ++chunks_;
  return absl::OkStatus();
}

absl::Status MapImportWriter::AddTrailer(const v1::MapExportTrailer& trailer) {
  if (absl::Status closed = CloseFile(); !closed.ok()) return closed;
  // Files with no bytes have no chunks.
  while (next_file_ < static_cast<uint32_t>(header_->files_size()) && header_->files(next_file_).bytes() == 0) {
    if (absl::Status opened = OpenFile(next_file_); !opened.ok()) return opened;
    if (absl::Status closed = CloseFile(); !closed.ok()) return closed;
  }
  if (next_file_ != static_cast<uint32_t>(header_->files_size())) {
    return Damaged(absl::StrCat("the trailer came after ", next_file_, " of ", header_->files_size(), " files"));
  }
  if (trailer.chunks() != chunks_ || trailer.bytes() != bytes_) {
    return Damaged(absl::StrCat("the trailer counts ", trailer.chunks(), " chunks of ", trailer.bytes(),
                                " bytes; the stream held ", chunks_, " of ", bytes_));
  }
  trailer_ = true;
  return absl::OkStatus();
}

absl::Status MapImportWriter::Finish() const {
  if (!header_) return Damaged("the stream is empty");
  if (!trailer_) {
    return Damaged(absl::StrCat("the stream ended after ", chunks_, " chunks (", bytes_, " bytes), before its trailer"));
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
