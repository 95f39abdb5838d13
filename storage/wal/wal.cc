#include "storage/wal/wal.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace fremen::storage {

namespace {

constexpr size_t kRecordHeader = 16;  // length, CRC, LSN
constexpr uint32_t kMaxPayload = 256u << 20;

absl::Status ErrnoStatus(const std::string& what) {
  const int e = errno;
  const std::string message = absl::StrCat(what, ": ", std::strerror(e));
  return e == ENOSPC ? absl::ResourceExhaustedError(message) : absl::InternalError(message);
}

void PutU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void PutU64(std::vector<uint8_t>& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
uint32_t GetU32(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = v << 8 | p[i];
  return v;
}
uint64_t GetU64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = v << 8 | p[i];
  return v;
}

uint32_t RecordCrc(const uint8_t* lsn_bytes, std::span<const uint8_t> payload) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, lsn_bytes, 8);
  crc = crc32(crc, payload.data(), static_cast<uInt>(payload.size()));
  return static_cast<uint32_t>(crc);
}

std::string SegmentPath(const std::string& dir, uint64_t first_lsn) {
  return absl::StrFormat("%s/wal-%020d.log", dir, first_lsn);
}

// First LSNs of the segments in dir, oldest first.
absl::StatusOr<std::vector<uint64_t>> ListSegments(const std::string& dir) {
  std::vector<uint64_t> firsts;
  DIR* d = opendir(dir.c_str());
  if (!d) {
    if (errno == ENOENT) return firsts;
    return ErrnoStatus(absl::StrCat("opendir ", dir));
  }
  while (dirent* e = readdir(d)) {
    uint64_t first;
    char tail;
    if (std::sscanf(e->d_name, "wal-%20" SCNu64 ".lo%c", &first, &tail) == 2 && tail == 'g') firsts.push_back(first);
  }
  closedir(d);
  std::sort(firsts.begin(), firsts.end());
  return firsts;
}

absl::StatusOr<std::vector<uint8_t>> ReadFile(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return ErrnoStatus(absl::StrCat("open ", path));
  std::vector<uint8_t> data;
  uint8_t chunk[1 << 16];
  for (;;) {
    const ssize_t n = read(fd, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      absl::Status s = ErrnoStatus(absl::StrCat("read ", path));
      close(fd);
      return s;
    }
    if (n == 0) break;
    data.insert(data.end(), chunk, chunk + n);
  }
  close(fd);
  return data;
}

absl::Status SyncDir(const std::string& dir) {
  const int fd = open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return ErrnoStatus(absl::StrCat("open ", dir));
  const int rc = fsync(fd);
  close(fd);
  return rc == 0 ? absl::OkStatus() : ErrnoStatus(absl::StrCat("fsync ", dir));
}

struct SegmentScan {
  uint64_t intact_bytes = 0;  // length of the prefix made of intact records
  bool torn = false;
};

// Walks the records of one segment whose first record must carry `expected_lsn`.
absl::StatusOr<SegmentScan> ScanSegment(const std::vector<uint8_t>& data, uint64_t& expected_lsn, uint64_t after_lsn,
                                        const std::function<absl::Status(uint64_t, std::span<const uint8_t>)>& f,
                                        uint64_t& delivered) {
  SegmentScan scan;
  size_t pos = 0;
  while (pos < data.size()) {
    if (data.size() - pos < kRecordHeader) break;
    const uint32_t length = GetU32(&data[pos]);
    if (length > kMaxPayload || data.size() - pos - kRecordHeader < length) break;
    const uint64_t lsn = GetU64(&data[pos + 8]);
    const std::span<const uint8_t> payload(&data[pos + kRecordHeader], length);
    if (GetU32(&data[pos + 4]) != RecordCrc(&data[pos + 8], payload) || lsn != expected_lsn) break;
    if (lsn > after_lsn) {
      if (absl::Status s = f(lsn, payload); !s.ok()) return s;
      ++delivered;
    }
    ++expected_lsn;
    pos += kRecordHeader + length;
  }
  scan.intact_bytes = pos;
  scan.torn = pos < data.size();
  return scan;
}

}  // namespace

absl::StatusOr<WalReplayResult> ReplayWal(const std::string& dir, uint64_t after_lsn,
                                          const std::function<absl::Status(uint64_t, std::span<const uint8_t>)>& f) {
  WalReplayResult result;
  auto firsts = ListSegments(dir);
  if (!firsts.ok()) return firsts.status();
  uint64_t expected = firsts->empty() ? 1 : firsts->front();
  for (size_t i = 0; i < firsts->size(); ++i) {
    const uint64_t first = (*firsts)[i];
    if (first != expected) {
      return absl::DataLossError(absl::StrCat("write-ahead log ", dir, ": segment ", first, " does not follow LSN ",
                                              expected - 1, " (a segment is missing)"));
    }
    const bool last = i + 1 == firsts->size();
    // Segments wholly covered by the checkpoint need no reading, only their LSN range.
    if (!last && (*firsts)[i + 1] - 1 <= after_lsn) {
      expected = (*firsts)[i + 1];
      continue;
    }
    auto data = ReadFile(SegmentPath(dir, first));
    if (!data.ok()) return data.status();
    auto scan = ScanSegment(*data, expected, after_lsn, f, result.records);
    if (!scan.ok()) return scan.status();
    if (scan->torn) {
      if (!last) {
        return absl::DataLossError(absl::StrCat("write-ahead log ", SegmentPath(dir, first), ": corrupt record at byte ",
                                                scan->intact_bytes, " before the end of the log"));
      }
      result.truncated_tail = true;
    }
  }
  result.last_lsn = expected - 1;
  return result;
}

absl::StatusOr<std::unique_ptr<WalWriter>> WalWriter::Open(const std::string& dir, const WalOptions& options) {
  if (mkdir(dir.c_str(), 0750) != 0 && errno != EEXIST) return ErrnoStatus(absl::StrCat("mkdir ", dir));
  auto writer = std::unique_ptr<WalWriter>(new WalWriter(dir, options));
  auto firsts = ListSegments(dir);
  if (!firsts.ok()) return firsts.status();
  if (firsts->empty()) {
    if (absl::Status s = writer->OpenSegment(1); !s.ok()) return s;
    return writer;
  }
  // Sizes of the live segments; the last one is cut after its last intact record.
  for (size_t i = 0; i < firsts->size(); ++i) {
    struct stat st;
    const std::string path = SegmentPath(dir, (*firsts)[i]);
    if (stat(path.c_str(), &st) != 0) return ErrnoStatus(absl::StrCat("stat ", path));
    writer->segments_.push_back({(*firsts)[i], static_cast<uint64_t>(st.st_size)});
  }
  const uint64_t last_first = firsts->back();
  const std::string last_path = SegmentPath(dir, last_first);
  uint64_t expected = last_first;
  uint64_t ignored = 0;
  auto data = ReadFile(last_path);
  if (!data.ok()) return data.status();
  auto scan = ScanSegment(*data, expected, UINT64_MAX, [](uint64_t, auto) { return absl::OkStatus(); }, ignored);
  if (!scan.ok()) return scan.status();
  if (scan->torn && truncate(last_path.c_str(), static_cast<off_t>(scan->intact_bytes)) != 0) {
    return ErrnoStatus(absl::StrCat("truncate ", last_path));
  }
  writer->segments_.back().bytes = scan->intact_bytes;
  writer->fd_ = open(last_path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (writer->fd_ < 0) return ErrnoStatus(absl::StrCat("open ", last_path));
  if (scan->torn && fdatasync(writer->fd_) != 0) return ErrnoStatus(absl::StrCat("fdatasync ", last_path));
  writer->segment_size_ = scan->intact_bytes;
  // Only the last segment is read: older ones are the recovery's business (ReplayWal), and most
  // are covered by the checkpoint anyway.
  writer->next_lsn_ = expected;
  writer->durable_lsn_ = expected - 1;
  for (const Segment& s : writer->segments_) writer->bytes_ += s.bytes;
  return writer;
}

WalWriter::~WalWriter() {
  if (fd_ >= 0) close(fd_);
}

absl::Status WalWriter::OpenSegment(uint64_t first_lsn) {
  const std::string path = SegmentPath(dir_, first_lsn);
  const int fd = open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_EXCL | O_CLOEXEC, 0640);
  if (fd < 0) return ErrnoStatus(absl::StrCat("create ", path));
  if (absl::Status s = SyncDir(dir_); !s.ok()) {
    close(fd);
    return s;
  }
  if (fd_ >= 0) close(fd_);
  fd_ = fd;
  segment_size_ = 0;
  segments_.push_back({first_lsn, 0});
  return absl::OkStatus();
}

uint64_t WalWriter::Append(std::span<const uint8_t> payload) {
  const uint64_t lsn = next_lsn_++;
  if (buffer_.empty()) first_buffered_lsn_ = lsn;
  uint8_t lsn_bytes[8];
  for (int i = 0; i < 8; ++i) lsn_bytes[i] = static_cast<uint8_t>(lsn >> (8 * i));
  PutU32(buffer_, static_cast<uint32_t>(payload.size()));
  PutU32(buffer_, RecordCrc(lsn_bytes, payload));
  PutU64(buffer_, lsn);
  buffer_.insert(buffer_.end(), payload.begin(), payload.end());
  return lsn;
}

absl::Status WalWriter::Sync() {
  if (!latched_.ok()) return latched_;
  if (buffer_.empty()) return absl::OkStatus();
  absl::Status status = options_.inject_fault ? options_.inject_fault() : absl::OkStatus();
  if (status.ok() && segment_size_ >= options_.segment_bytes) status = OpenSegment(first_buffered_lsn_);
  size_t written = 0;
  while (status.ok() && written < buffer_.size()) {
    const ssize_t n = write(fd_, buffer_.data() + written, buffer_.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) status = ErrnoStatus("write to the write-ahead log");
    else written += static_cast<size_t>(n);
  }
  if (status.ok() && fdatasync(fd_) != 0) status = ErrnoStatus("fdatasync of the write-ahead log");
  if (!status.ok()) {
    latched_ = status;
    return status;
  }
  segment_size_ += buffer_.size();
  segments_.back().bytes += buffer_.size();
  bytes_ += buffer_.size();
  buffer_.clear();
  durable_lsn_ = next_lsn_ - 1;
  return absl::OkStatus();
}

absl::Status WalWriter::DropThrough(uint64_t lsn) {
  while (segments_.size() > 1 && segments_[1].first_lsn - 1 <= lsn) {
    const std::string path = SegmentPath(dir_, segments_.front().first_lsn);
    if (unlink(path.c_str()) != 0 && errno != ENOENT) return ErrnoStatus(absl::StrCat("unlink ", path));
    bytes_ -= segments_.front().bytes;
    segments_.erase(segments_.begin());
  }
  return absl::OkStatus();
}

}  // namespace fremen::storage
