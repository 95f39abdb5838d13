#include "storage/wal/wal.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstring>
#include <optional>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {

constexpr size_t kRecordHeader = 16;  // length, CRC, LSN
constexpr uint32_t kMaxPayload = 256u << 20;

uint32_t RecordCrc(const uint8_t* lsn_bytes, std::span<const uint8_t> payload) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, lsn_bytes, 8);
  crc = crc32(crc, payload.data(), static_cast<uInt>(payload.size()));
  return static_cast<uint32_t>(crc);
}

std::string SegmentPath(const std::string& dir, uint64_t first_lsn) {
  return absl::StrFormat("%s/wal-%020d.log", dir, first_lsn);
}

using RecordFn = std::function<absl::Status(uint64_t, std::span<const uint8_t>)>;

// First LSNs of the segments in dir, oldest first. Only names the writer makes count: a stray
// "wal-….log.tmp" or an editor's backup is no segment.
absl::StatusOr<std::vector<uint64_t>> ListSegments(Env* env, const std::string& dir) {
  std::vector<uint64_t> firsts;
  auto names = env->ListDir(dir);
  if (absl::IsNotFound(names.status())) return firsts;
  if (!names.ok()) return names.status();
  constexpr std::string_view kPrefix = "wal-", kSuffix = ".log";
  constexpr size_t kDigits = 20;
  for (const std::string& name : *names) {
    if (name.size() != kPrefix.size() + kDigits + kSuffix.size() || !name.starts_with(kPrefix) ||
        !name.ends_with(kSuffix)) {
      continue;
    }
    const std::string_view digits = std::string_view(name).substr(kPrefix.size(), kDigits);
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    uint64_t first = 0;
    for (char c : digits) first = first * 10 + static_cast<uint64_t>(c - '0');
    firsts.push_back(first);
  }
  std::sort(firsts.begin(), firsts.end());
  return firsts;
}

struct Record {
  size_t pos = 0;
  uint64_t lsn = 0;
  std::span<const uint8_t> payload;
};

// The record at data[pos] if it is complete and its CRC holds; `plausible` vets the LSN before the
// CRC is computed (scanning forward tries every byte).
template <typename Plausible>
std::optional<Record> IntactRecordAt(std::span<const uint8_t> data, size_t pos, Plausible plausible) {
  if (data.size() - pos < kRecordHeader) return std::nullopt;
  const uint32_t length = model::DecodeFixed32(&data[pos]);
  if (length > kMaxPayload || data.size() - pos - kRecordHeader < length) return std::nullopt;
  const uint64_t lsn = model::DecodeFixed64(&data[pos + 8]);
  if (!plausible(lsn)) return std::nullopt;
  const std::span<const uint8_t> payload = data.subspan(pos + kRecordHeader, length);
  if (model::DecodeFixed32(&data[pos + 4]) != RecordCrc(&data[pos + 8], payload)) return std::nullopt;
  return Record{pos, lsn, payload};
}

// The first intact record at or after `from` whose LSN could follow `expected` in this segment (a
// record is at least a header long, so no later LSN fits in the bytes left).
std::optional<Record> FindIntactRecord(std::span<const uint8_t> data, size_t from, uint64_t expected) {
  const uint64_t most = expected + (data.size() - std::min(from, data.size())) / kRecordHeader;
  for (size_t pos = from; pos + kRecordHeader <= data.size(); ++pos) {
    if (auto r = IntactRecordAt(data, pos, [&](uint64_t lsn) { return lsn >= expected && lsn <= most; })) return r;
  }
  return std::nullopt;
}

struct SegmentScan {
  enum class End { kClean, kTornTail, kCorrupt };
  End end = End::kClean;
  uint64_t intact_bytes = 0;  // the prefix made of intact records in sequence
  std::string damage;         // kCorrupt: what is wrong where
};

// Walks the records of one segment whose first record must carry `expected_lsn`, passing those
// after `after_lsn` to f (if any). Stops at the first record that is not intact and in sequence,
// and tells a torn tail (nothing intact after it) from corruption.
absl::StatusOr<SegmentScan> ScanSegment(const std::string& path, std::span<const uint8_t> data, uint64_t& expected_lsn,
                                        uint64_t after_lsn, const RecordFn& f, uint64_t& delivered,
                                        uint64_t& position) {
  SegmentScan scan;
  size_t pos = 0;
  while (pos < data.size()) {
    const auto record = IntactRecordAt(data, pos, [](uint64_t) { return true; });
    if (!record || record->lsn != expected_lsn) break;
    if (f && record->lsn > after_lsn) {
      position = pos;  // where f refused, if it does
      if (absl::Status s = f(record->lsn, record->payload); !s.ok()) return s;
      ++delivered;
    }
    ++expected_lsn;
    pos += kRecordHeader + record->payload.size();
  }
  scan.intact_bytes = pos;
  position = pos;
  if (pos == data.size()) return scan;
  const std::string where =
      absl::StrCat("write-ahead log ", path, ": record at byte ", pos, " (LSN ", expected_lsn, ")");
  if (auto out_of_sequence = IntactRecordAt(data, pos, [](uint64_t) { return true; })) {
    scan.end = SegmentScan::End::kCorrupt;
    scan.damage = absl::StrCat(where, " is intact but carries LSN ", out_of_sequence->lsn, "; nothing was cut");
  } else if (auto next = FindIntactRecord(data, pos + 1, expected_lsn)) {
    scan.end = SegmentScan::End::kCorrupt;
    scan.damage = absl::StrCat(where, " is damaged and an intact record (LSN ", next->lsn, ") follows at byte ",
                               next->pos, ": corruption, not a torn write; nothing was cut");
  } else {
    scan.end = SegmentScan::End::kTornTail;
  }
  return scan;
}

std::span<const uint8_t> Bytes(const std::string& s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

}  // namespace

namespace {

// What lies from (segment `index`, byte `offset`) on: its bytes, and the highest LSN of an intact
// record there (any record whose CRC holds and whose LSN is at least `lsn`).
void MeasureRest(Env* env, const std::string& dir, const std::vector<uint64_t>& firsts, size_t index, uint64_t offset,
                 uint64_t lsn, WalStop& stop) {
  for (size_t i = index; i < firsts.size(); ++i) {
    auto data = env->ReadFile(SegmentPath(dir, firsts[i]));
    if (!data.ok()) continue;
    const std::span<const uint8_t> bytes = Bytes(*data);
    size_t pos = i == index ? std::min<uint64_t>(offset, bytes.size()) : 0;
    stop.bytes_after += bytes.size() - pos;
    if (i == index) ++pos;  // the record there is the damaged one
    while (pos + kRecordHeader <= bytes.size()) {
      const auto record = IntactRecordAt(bytes, pos, [&](uint64_t l) { return l >= lsn && l - lsn < (1ull << 40); });
      if (!record) {
        ++pos;
        continue;
      }
      stop.highest_lsn_after = std::max(stop.highest_lsn_after, record->lsn);
      pos += kRecordHeader + record->payload.size();
    }
  }
}

}  // namespace

absl::StatusOr<WalReplayResult> ReplayWal(const std::string& dir, uint64_t after_lsn, const RecordFn& f, Env* env,
                                          WalStop* stop) {
  WalReplayResult result;
  auto firsts = ListSegments(env, dir);
  if (!firsts.ok()) return firsts.status();
  uint64_t expected = firsts->empty() ? 1 : firsts->front();
  for (size_t i = 0; i < firsts->size(); ++i) {
    const uint64_t first = (*firsts)[i];
    const std::string path = SegmentPath(dir, first);
    if (first != expected) {
      // A recovery whose log ended below its checkpoints opens a new segment at its LSN floor: the
      // LSNs skipped are covered by the checkpoint. Any other gap, or an overlap, is damage.
      if (first < expected || first - 1 > after_lsn) {
        if (stop != nullptr) {
          *stop = WalStop{path, 0, expected, 0, 0};
          MeasureRest(env, dir, *firsts, i, 0, expected, *stop);
        }
        return absl::DataLossError(absl::StrCat("write-ahead log ", path, ": starts at LSN ", first,
                                                " but the log before it ends at LSN ", expected - 1,
                                                first < expected ? " (segments overlap)" : " (a segment is missing)"));
      }
      expected = first;
    }
    const bool last = i + 1 == firsts->size();
    // Segments wholly covered by the checkpoint need no reading, only their LSN range.
    if (!last && (*firsts)[i + 1] - 1 <= after_lsn) {
      expected = (*firsts)[i + 1];
      continue;
    }
    auto data = env->ReadFile(path);
    if (!data.ok()) return data.status();
    uint64_t position = 0;
    auto scan = ScanSegment(path, Bytes(*data), expected, after_lsn, f, result.records, position);
    const bool stopped =
        !scan.ok() || scan->end == SegmentScan::End::kCorrupt || (scan->end == SegmentScan::End::kTornTail && !last);
    if (stopped && stop != nullptr) {
      *stop = WalStop{path, position, expected, 0, 0};
      MeasureRest(env, dir, *firsts, i, position, expected, *stop);
    }
    if (!scan.ok()) return scan.status();
    if (scan->end == SegmentScan::End::kCorrupt) return absl::DataLossError(scan->damage);
    if (last) {
      result.newest_segment_scanned = true;
      result.newest_segment_first = first;
      result.newest_segment_intact_bytes = scan->intact_bytes;
    }
    if (scan->end == SegmentScan::End::kTornTail) {
      if (!last) {
        return absl::DataLossError(absl::StrCat("write-ahead log ", path, ": record at byte ", scan->intact_bytes,
                                                " (LSN ", expected,
                                                ") is damaged or incomplete and newer segments "
                                                "follow: corruption, not a torn write"));
      }
      result.truncated_tail = true;
      result.torn_tail_file = path;
      result.torn_tail_offset = scan->intact_bytes;
      result.torn_tail_bytes = data->size() - scan->intact_bytes;
    }
  }
  result.last_lsn = expected - 1;
  return result;
}

absl::StatusOr<std::unique_ptr<WalWriter>> WalWriter::Open(const std::string& dir, const WalOptions& options) {
  Env* env = options.env;
  if (absl::Status s = env->CreateDir(dir); !s.ok()) return s;
  auto writer = std::unique_ptr<WalWriter>(new WalWriter(dir, options));
  auto firsts = ListSegments(env, dir);
  if (!firsts.ok()) return firsts.status();
  const uint64_t floor = std::max<uint64_t>(options.min_next_lsn, 1);
  if (firsts->empty()) {
    if (absl::Status s = writer->OpenSegment(floor); !s.ok()) return s;
    writer->next_lsn_ = floor;
    writer->durable_lsn_ = floor - 1;
    return writer;
  }
  for (const uint64_t first : *firsts) {
    auto size = env->FileSize(SegmentPath(dir, first));
    if (!size.ok()) return size.status();
    writer->segments_.push_back({first, *size});
  }
  // Only the newest segment is read: older ones are the recovery's business (ReplayWal), and most
  // are covered by the checkpoint anyway.
  const uint64_t last_first = firsts->back();
  const std::string last_path = SegmentPath(dir, last_first);
  uint64_t expected = last_first;
  uint64_t intact_bytes = 0;
  if (const WalReplayResult* replayed = options.replayed;
      replayed != nullptr && replayed->newest_segment_scanned && replayed->newest_segment_first == last_first) {
    // The replay read this segment a moment ago and stopped at its last intact record.
    expected = replayed->last_lsn + 1;
    intact_bytes = replayed->newest_segment_intact_bytes;
  } else {
    auto data = env->ReadFile(last_path);
    if (!data.ok()) return data.status();
    uint64_t ignored = 0;
    uint64_t ignored_position = 0;
    auto scan = ScanSegment(last_path, Bytes(*data), expected, UINT64_MAX, nullptr, ignored, ignored_position);
    if (!scan.ok()) return scan.status();
    if (scan->end == SegmentScan::End::kCorrupt) return absl::DataLossError(scan->damage);
    intact_bytes = scan->intact_bytes;
  }
  if (intact_bytes < writer->segments_.back().bytes) {  // a torn tail
    if (absl::Status s = env->Truncate(last_path, intact_bytes); !s.ok()) return s;
  }
  writer->segments_.back().bytes = intact_bytes;
  auto file = env->NewAppendableFile(last_path);
  if (!file.ok()) return file.status();
  writer->file_ = *std::move(file);
  writer->segment_size_ = intact_bytes;
  writer->next_lsn_ = expected;
  for (const Segment& s : writer->segments_) writer->bytes_ += s.bytes;
  if (writer->next_lsn_ < floor) {
    // The log ends below a checkpoint (its tail was lost or cut): new records start at the floor,
    // in a segment named after it, so that none is taken for checkpointed.
    if (absl::Status s = writer->OpenSegment(floor); !s.ok()) return s;
    writer->next_lsn_ = floor;
  }
  writer->durable_lsn_ = writer->next_lsn_ - 1;
  return writer;
}

WalWriter::~WalWriter() {
  if (file_) (void)file_->Close();
}

absl::Status WalWriter::OpenSegment(uint64_t first_lsn) {
  auto file = env_->NewWritableFile(SegmentPath(dir_, first_lsn));
  if (!file.ok()) return file.status();
  if (absl::Status s = env_->SyncDir(dir_); !s.ok()) return s;
  if (file_) (void)file_->Close();  // synced already: every byte in it was acknowledged
  file_ = *std::move(file);
  segment_size_ = 0;
  segments_.push_back({first_lsn, 0});
  return absl::OkStatus();
}

uint64_t WalWriter::Append(std::span<const uint8_t> payload) {
  const uint64_t lsn = next_lsn_++;
  if (buffer_.empty()) first_buffered_lsn_ = lsn;
  uint8_t header[kRecordHeader];
  model::EncodeFixed32(header, static_cast<uint32_t>(payload.size()));
  model::EncodeFixed64(header + 8, lsn);
  model::EncodeFixed32(header + 4, RecordCrc(header + 8, payload));
  buffer_.insert(buffer_.end(), header, header + kRecordHeader);
  buffer_.insert(buffer_.end(), payload.begin(), payload.end());
  return lsn;
}

absl::Status WalWriter::Sync() {
  if (!latched_.ok()) return latched_;
  if (buffer_.empty()) return absl::OkStatus();
  absl::Status status;
  if (segment_size_ >= options_.segment_bytes) status = OpenSegment(first_buffered_lsn_);
  if (status.ok()) status = file_->Append(buffer_);
  if (status.ok()) status = file_->Sync();
  if (!status.ok()) {
    latched_ = absl::Status(status.code(), absl::StrCat("write-ahead log: ", status.message()));
    // The batches of this group are answered with the error: cut what may have reached the file of
    // them, so that a later recovery does not apply them after all. Best effort — if the cut fails
    // too, they may come back, and a client's retry of one is then recognised as a duplicate.
    if (!segments_.empty()) (void)env_->Truncate(SegmentPath(dir_, segments_.back().first_lsn), segment_size_);
    return latched_;
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
    if (absl::Status s = env_->Unlink(path); !s.ok() && !absl::IsNotFound(s)) return s;
    bytes_ -= segments_.front().bytes;
    segments_.erase(segments_.begin());
  }
  return absl::OkStatus();
}

}  // namespace fremen::storage
