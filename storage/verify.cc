#include "storage/verify.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <functional>
#include <span>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "storage/batch.h"
#include "storage/catalog.h"
#include "storage/cell_key.h"
#include "storage/data_dir_format.h"
#include "storage/dedup_table.h"
#include "storage/isolated_child.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/record_codec.h"
#include "storage/model/varint.h"
#include "storage/model/kernels/wide_bodies.h"
#include "storage/shard_record_checks.h"
#include "storage/shard_records.h"
#include "storage/static_bricks.h"
#include "storage/wal/wal.h"

namespace fremen::storage {

namespace {

namespace sr = shard_records;

// The log's record header (storage/wal/wal.h): u32 payload length | u32 CRC | u64 LSN.
constexpr uint64_t kLogRecordHeader = 16;
// The first byte of a log record (storage/map_store.cc).
constexpr uint8_t kBatchRecord = 'B';
constexpr uint8_t kPublishRecord = 'P';

std::string ShardFile(uint32_t shard) { return absl::StrCat("shard-", shard, "/data.mdb"); }
std::string_view View(std::span<const uint8_t> b) { return {reinterpret_cast<const char*>(b.data()), b.size()}; }

uint64_t FileSize(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
}

// What one shard's check found; what an isolated child sends back.
struct ShardResult {
  ShardVerifyReport report;
  std::vector<VerifyProblem> problems;
  std::vector<std::string> notes;
  bool deadline_exceeded = false;
};

// Checks every record of one open shard environment.
class ShardChecker {
 public:
  ShardChecker(const MapInfo& info, const model::ModelSettings& settings, uint32_t shard, ShardResult& result)
      : info_(info), shard_(shard), checks_(info, settings, shard), result_(result) {
    result_.report.shard = shard;
  }

  void Check(const LmdbEnv& env) {
    const absl::Status read = env.Read([&](LmdbTxn& txn) -> absl::Status {
      ScanDb(txn, sr::kStaticDb, [&](uint64_t brick, std::string_view value) { return CheckStatic(brick, value); });
      ScanDb(txn, sr::kDynamicDb, [&](uint64_t key, std::string_view value) { return CheckDynamic(key, value); });
      ScanDb(txn, sr::kPublishedDb, [&](uint64_t key, std::string_view value) { return CheckPublished(key, value); });
      ScanDb(txn, sr::kLosslessDb, [&](uint64_t key, std::string_view value) { return CheckLossless(key, value); });
      ScanDb(txn, sr::kWideDb, [&](uint64_t key, std::string_view value) { return CheckWide(key, value); });
      ScanDb(txn, sr::kLabelsDb, [&](uint64_t key, std::string_view value) { return CheckLabel(key, value); });
      CheckMeta(txn);
      return absl::OkStatus();
    });
    if (!read.ok()) Problem("", read.message());
    result_.report.read = read.ok() && !scan_failed_;
  }

 private:
  void Problem(std::string where, absl::string_view what) {
    result_.problems.push_back({ShardFile(shard_), std::move(where), std::string(what)});
  }

  // Calls f(key, value) for every record of a database; a record whose checksum fails or that f
  // rejects is a problem and the scan goes on. An LMDB error ends this database's scan (LMDB
  // cannot step past it).
  void ScanDb(LmdbTxn& txn, const char* family, const std::function<absl::Status(uint64_t, std::string_view)>& f) {
    auto db = txn.Db(family);
    if (absl::IsNotFound(db.status())) return;  // never written
    if (!db.ok()) {
      Problem(family, db.status().message());
      scan_failed_ = true;
      return;
    }
    std::optional<uint64_t> last_key;
    const absl::Status scanned = txn.ScanChecked(*db, {}, {}, [&](auto key, auto checked) {
      ++result_.report.records;
      if (!checked.ok()) {  // a checksum mismatch: reported, and the scan goes on
        Problem(absl::StrCat(family, " record #", result_.report.records), checked.status().message());
        return true;
      }
      const std::span<const uint8_t> value = *checked;
      result_.report.record_bytes += key.size() + value.size();
      if (key.size() != 8) {
        Problem(absl::StrCat(family, " record #", result_.report.records),
                absl::StrCat("a key of ", key.size(), " bytes, not 8"));
        return true;
      }
      const uint64_t k = KeyFromBytes(key.data());
      last_key = k;
      if (absl::Status s = f(k, View(value)); !s.ok()) Problem(absl::StrCat(family, " record of key ", k), s.message());
      return true;
    });
    if (!scanned.ok()) {
      Problem(last_key ? absl::StrCat(family, " after key ", *last_key) : std::string(family),
              absl::StrCat(scanned.message(), " (the rest of this database was not read)"));
      scan_failed_ = true;
    }
  }

  absl::Status CheckStatic(uint64_t brick, std::string_view value) {
    StaticBrick decoded;
    const absl::Status checked = checks_.Static(brick, value, &decoded);
    decoded.ForEach([&](uint32_t i, const model::StaticState&) { static_keys_.insert(brick << kBrickBits | i); });
    return checked;
  }

  absl::Status CheckDynamic(uint64_t key, std::string_view value) {
    if (absl::Status s = checks_.Dynamic(key, value); !s.ok()) return s;
    dynamic_keys_.insert(key);
    if (static_keys_.contains(key)) return absl::DataLossError("the state is also stored as never changed");
    return absl::OkStatus();
  }

  absl::Status CheckLossless(uint64_t key, std::string_view value) {
    if (info_.lossless_sampling_period <= 0) return absl::DataLossError("a lossless history in a map without them");
    if (!dynamic_keys_.contains(key)) return absl::DataLossError("a lossless history without its state");
    return checks_.Lossless(value);
  }

  absl::Status CheckPublished(uint64_t key, std::string_view value) {
    if (!dynamic_keys_.contains(key)) return absl::DataLossError("a published model without its state");
    return checks_.Published(value);
  }

  absl::Status CheckWide(uint64_t key, std::string_view value) {
    if (!dynamic_keys_.contains(key)) return absl::DataLossError("a wide body without its state");
    return checks_.Wide(value);
  }

  absl::Status CheckLabel(uint64_t key, std::string_view value) { return checks_.Label(key, value); }

  // The meta records are named, not keyed by state. Read after the states (the touched list names
  // changed states).
  void CheckMeta(LmdbTxn& txn) {
    auto meta = txn.Db(sr::kMetaDb);
    if (absl::IsNotFound(meta.status())) return;
    if (!meta.ok()) {
      Problem(sr::kMetaDb, meta.status().message());
      return;
    }
    const absl::Status scanned = txn.ScanChecked(*meta, {}, {}, [&](auto key, auto checked) {
      ++result_.report.records;
      const std::string_view name = View(key);
      const std::string where = absl::StrCat("meta record ", absl::string_view(name.data(), name.size()));
      if (!checked.ok()) {
        Problem(where, checked.status().message());
        return true;
      }
      const std::span<const uint8_t> value = *checked;
      result_.report.record_bytes += key.size() + value.size();
      if (name == sr::kLsnKey) {
        auto lsn = sr::DecodeCheckpointLsn(value);
        if (lsn.ok())
          result_.report.checkpoint_lsn = *lsn;
        else
          Problem(where, lsn.status().message());
      } else if (name == sr::kDedupKey) {
        if (auto table = DedupTable::Decode(View(value)); !table.ok()) Problem(where, table.status().message());
      } else if (name == sr::kTouchedKey) {
        auto keys = sr::DecodeTouched(View(value));
        if (!keys.ok()) {
          Problem(where, keys.status().message());
        } else {
          for (uint64_t k : *keys) {
            if (!dynamic_keys_.contains(k)) {
              Problem(where, absl::StrCat("state ", k, " is not a changed state of the shard"));
              break;
            }
          }
        }
      } else {
        result_.notes.push_back(absl::StrCat(ShardFile(shard_), ": meta record \"",
                                             absl::CHexEscape(absl::string_view(name.data(), name.size())),
                                             "\" is not one this version knows"));
      }
      return true;
    });
    if (!scanned.ok()) {
      Problem(sr::kMetaDb, scanned.message());
      scan_failed_ = true;
    }
  }

  const MapInfo& info_;
  const uint32_t shard_;
  const ShardRecordChecks checks_;
  ShardResult& result_;
  bool scan_failed_ = false;
  absl::flat_hash_set<uint64_t> static_keys_, dynamic_keys_;
};

ShardResult CheckShard(const std::string& dir, const MapInfo& info, const model::ModelSettings& settings,
                       uint32_t shard, bool live) {
  ShardResult result;
  result.report.shard = shard;
  const std::string shard_dir = absl::StrCat(dir, "/shard-", shard);
  const std::string file = shard_dir + "/data.mdb";
  struct stat st;
  if (stat(file.c_str(), &st) != 0) {
    result.problems.push_back({ShardFile(shard), "", absl::StrCat("cannot be read: ", std::strerror(errno))});
    return result;
  }
  result.report.file_bytes = static_cast<uint64_t>(st.st_size);
  LmdbOptions options;
  options.read_only = true;
  options.no_lock = !live;
  options.databases = sr::AllDatabases();
  // Map the whole file (a read-only environment cannot grow its map).
  options.initial_map_size = std::max<size_t>(options.initial_map_size, static_cast<size_t>(st.st_size));
  auto env = LmdbEnv::Open(shard_dir, options);
  if (!env.ok()) {
    result.problems.push_back({ShardFile(shard), "", absl::StrCat("cannot be opened: ", env.status().message())});
    return result;
  }
  ShardChecker checker(info, settings, shard, result);
  checker.Check(**env);
  return result;
}

// --- the isolated child's report, over a pipe ---

void PutString(std::string& out, std::string_view s) {
  model::PutVarint64(&out, s.size());
  out += s;
}

std::string EncodeResult(const ShardResult& r) {
  std::string out;
  model::PutVarint64(&out, r.report.records);
  model::PutVarint64(&out, r.report.record_bytes);
  model::PutVarint64(&out, r.report.file_bytes);
  model::PutVarint64(&out, r.report.checkpoint_lsn ? 1 : 0);
  model::PutVarint64(&out, r.report.checkpoint_lsn.value_or(0));
  model::PutVarint64(&out, r.report.read ? 1 : 0);
  model::PutVarint64(&out, r.problems.size());
  for (const VerifyProblem& p : r.problems) {
    PutString(out, p.file);
    PutString(out, p.where);
    PutString(out, p.what);
  }
  model::PutVarint64(&out, r.notes.size());
  for (const std::string& n : r.notes) PutString(out, n);
  return out;
}

absl::StatusOr<ShardResult> DecodeResult(std::string_view bytes, uint32_t shard) {
  model::ByteReader r(bytes, "verifier child report");
  ShardResult result;
  result.report.shard = shard;
  result.report.records = r.Varint("records");
  result.report.record_bytes = r.Varint("record bytes");
  result.report.file_bytes = r.Varint("file bytes");
  const bool has_lsn = r.Varint("has lsn") != 0;
  const uint64_t lsn = r.Varint("lsn");
  if (has_lsn) result.report.checkpoint_lsn = lsn;
  result.report.read = r.Varint("read") != 0;
  const auto string = [&](std::string_view field) { return std::string(r.Bytes(r.Varint(field), field)); };
  for (uint64_t i = 0, n = r.Varint("problems"); i < n && r.ok(); ++i) {
    VerifyProblem p;
    p.file = string("file");
    p.where = string("where");
    p.what = string("what");
    result.problems.push_back(std::move(p));
  }
  for (uint64_t i = 0, n = r.Varint("notes"); i < n && r.ok(); ++i) result.notes.push_back(string("note"));
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  return result;
}

// CheckShard in a forked child (storage/isolated_child.h), which sends its result over a pipe.
ShardResult CheckShardIsolated(const std::string& dir, const MapInfo& info, const model::ModelSettings& settings,
                               uint32_t shard, bool live, absl::Time deadline) {
  ShardResult failed;
  failed.report.shard = shard;
  std::string bytes;
  auto exit = RunIsolated(
      [&](int fd) { return WriteAll(fd, EncodeResult(CheckShard(dir, info, settings, shard, live))); },
      [&](std::string_view chunk) { bytes.append(chunk); }, deadline);
  if (!exit.ok()) {
    failed.problems.push_back({ShardFile(shard), "", absl::StrCat("not verified: ", exit.status().message())});
    failed.deadline_exceeded = absl::IsDeadlineExceeded(exit.status());
    return failed;
  }
  if (exit->signal != 0) {
    failed.problems.push_back({ShardFile(shard), "", DescribeChildExit(*exit)});
    return failed;
  }
  if (!exit->ok()) {
    failed.problems.push_back({ShardFile(shard), "", absl::StrCat("not verified: ", DescribeChildExit(*exit))});
    return failed;
  }
  auto result = DecodeResult(bytes, shard);
  if (!result.ok()) {
    failed.problems.push_back({ShardFile(shard), "", absl::StrCat("not verified: ", result.status().message())});
    return failed;
  }
  return *std::move(result);
}

// --- the log ---

struct Segment {
  uint64_t first_lsn;
  std::string name;  // relative to the map directory
  uint64_t bytes;
};

std::vector<Segment> ListSegments(const std::string& wal_dir) {
  std::vector<Segment> segments;
  DIR* d = opendir(wal_dir.c_str());
  if (!d) return segments;
  while (dirent* e = readdir(d)) {
    uint64_t first;
    char tail;
    if (std::sscanf(e->d_name, "wal-%20" SCNu64 ".lo%c", &first, &tail) == 2 && tail == 'g') {
      segments.push_back({first, absl::StrCat("wal/", e->d_name), FileSize(absl::StrCat(wal_dir, "/", e->d_name))});
    }
  }
  closedir(d);
  std::sort(segments.begin(), segments.end(),
            [](const Segment& a, const Segment& b) { return a.first_lsn < b.first_lsn; });
  return segments;
}

// Where a record (or the end of the intact log) lies: the segment and its byte offset there.
class LogPosition {
 public:
  explicit LogPosition(const std::vector<Segment>& segments) : segments_(segments) {}
  // Called with every record in order.
  void Advance(uint64_t lsn, size_t payload_bytes) {
    while (index_ + 1 < segments_.size() && segments_[index_ + 1].first_lsn <= lsn) {
      ++index_;
      offset_ = 0;
    }
    record_offset_ = offset_;
    offset_ += kLogRecordHeader + payload_bytes;
  }
  const Segment* segment() const { return segments_.empty() ? nullptr : &segments_[index_]; }
  uint64_t record_offset() const { return record_offset_; }  // of the last record passed to Advance
  // Where the intact log ends: just after the last record, or at the start of the next segment
  // when that record filled its own (nullptr when there is no segment).
  std::pair<const Segment*, uint64_t> IntactEnd() const {
    if (segments_.empty()) return {nullptr, 0};
    if (index_ + 1 < segments_.size() && offset_ >= segments_[index_].bytes) return {&segments_[index_ + 1], 0};
    return {&segments_[index_], offset_};
  }

 private:
  const std::vector<Segment>& segments_;
  size_t index_ = 0;
  uint64_t offset_ = 0, record_offset_ = 0;
};

// Whether the bytes after the last intact record hold a complete record (so a damaged one, not a
// write cut short): its header is there and the length it gives fits in the file.
bool HoldsCompleteRecord(const std::string& path, uint64_t offset, uint64_t file_bytes) {
  if (file_bytes < offset + kLogRecordHeader) return false;
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  uint8_t header[4];
  const bool got = pread(fd, header, 4, static_cast<off_t>(offset)) == 4;
  close(fd);
  if (!got) return false;
  const uint64_t length =
      uint64_t{header[0]} | uint64_t{header[1]} << 8 | uint64_t{header[2]} << 16 | uint64_t{header[3]} << 24;
  return offset + kLogRecordHeader + length <= file_bytes;
}

void VerifyLog(const std::string& dir, bool live, VerifyReport& report) {
  const std::string wal_dir = dir + "/wal";
  LogVerifyReport& log = report.log;
  std::vector<Segment> segments;
  LogPosition position(segments);
  uint64_t last_seen = 0;
  const auto problem_at = [&](const Segment* segment, uint64_t offset, uint64_t lsn_before, std::string what) {
    report.problems.push_back({segment ? segment->name : "wal",
                               absl::StrCat("byte ", offset, " (after LSN ", lsn_before, ")"), std::move(what)});
  };
  // A live log is listed again after the replay: it only grows meanwhile (MapStore::Verify holds
  // off checkpoints, which drop segments), so the second list holds every segment replayed.
  segments = ListSegments(wal_dir);
  auto replayed = ReplayWal(wal_dir, 0, [&](uint64_t lsn, std::span<const uint8_t> payload) -> absl::Status {
    position.Advance(lsn, payload.size());
    last_seen = lsn;
    ++log.records;
    if (payload.size() == 1 && payload[0] == kPublishRecord) return absl::OkStatus();
    if (payload.empty() || payload[0] != kBatchRecord) {
      problem_at(position.segment(), position.record_offset(), lsn - 1,
                 absl::StrCat("record ", lsn, ": unknown record kind"));
      return absl::OkStatus();
    }
    if (auto batch = DecodeBatch(View(payload.subspan(1))); !batch.ok()) {
      problem_at(position.segment(), position.record_offset(), lsn - 1,
                 absl::StrCat("record ", lsn, ": ", batch.status().message()));
    }
    return absl::OkStatus();
  });
  if (live) segments = ListSegments(wal_dir);
  log.segments = segments.size();
  for (const Segment& s : segments) log.bytes += s.bytes;
  log.first_lsn = segments.empty() ? 0 : segments.front().first_lsn;
  const auto [end_segment, end_offset] = position.IntactEnd();
  if (!replayed.ok()) {
    problem_at(end_segment, end_offset, last_seen, std::string(replayed.status().message()));
    log.last_lsn = last_seen;
  } else {
    log.last_lsn = replayed->last_lsn;
    if (replayed->truncated_tail && end_segment != nullptr) {
      log.torn_tail_bytes = end_segment->bytes - std::min(end_offset, end_segment->bytes);
      if (end_segment != &segments.back()) {
        problem_at(end_segment, end_offset, log.last_lsn, "the log's intact records end before its newest segment");
      } else if (!live &&
                 HoldsCompleteRecord(absl::StrCat(dir, "/", end_segment->name), end_offset, end_segment->bytes)) {
        problem_at(end_segment, end_offset, log.last_lsn,
                   absl::StrCat("a damaged record (its checksum or LSN does not match); ", log.torn_tail_bytes,
                                " bytes from it to the end of the segment were not replayed"));
      } else {
        report.notes.push_back(absl::StrCat(
            end_segment->name, ": ", log.torn_tail_bytes, " bytes after LSN ", log.last_lsn, " at byte ", end_offset,
            live ? " (a record being written)" : ": a torn tail (never acknowledged; cut at the next start)"));
      }
    }
  }
  // Checkpoints against the log's range.
  std::optional<uint64_t> oldest, newest;
  uint32_t oldest_shard = 0, newest_shard = 0;
  for (const ShardVerifyReport& shard : report.shards) {
    const uint64_t lsn = shard.checkpoint_lsn.value_or(0);
    if (!oldest || lsn < *oldest) oldest = lsn, oldest_shard = shard.shard;
    if (!newest || lsn > *newest) newest = lsn, newest_shard = shard.shard;
  }
  if (!oldest) return;
  if (segments.empty()) {
    if (*newest > 0) {
      report.problems.push_back({"wal", "",
                                 absl::StrCat("no log segment, while shard-", newest_shard, "'s checkpoint covers LSN ",
                                              *newest, ": new records would reuse LSNs it covers")});
    }
    return;
  }
  if (log.first_lsn > *oldest + 1) {
    report.problems.push_back({segments.front().name, "",
                               absl::StrCat("a gap: shard-", oldest_shard, "'s checkpoint covers LSN ", *oldest,
                                            " but the log starts at LSN ", log.first_lsn, ", so records ", *oldest + 1,
                                            "..", log.first_lsn - 1, " are missing")});
  }
  const uint64_t log_end = std::max(log.last_lsn, log.first_lsn - 1);
  if (*newest > log_end) {
    report.problems.push_back({"wal", "",
                               absl::StrCat("shard-", newest_shard, "'s checkpoint covers LSN ", *newest,
                                            " but the log's last intact record is LSN ", log_end,
                                            ": new records would reuse LSNs the checkpoint covers")});
  }
}

VerifyReport Verify(const std::string& dir, const MapInfo& info, const VerifyOptions& options, bool with_log) {
  VerifyReport report;
  report.map = info.name;
  report.dir = dir;
  auto settings = ModelSettingsOf(info);
  if (!settings.ok()) {
    report.problems.push_back(
        {"map.info", "", absl::StrCat("the map's settings are invalid: ", settings.status().message())});
    return report;
  }
  if (info.shards == 0) {
    report.problems.push_back({"map.info", "", "the map has no shards"});
    return report;
  }
  (void)sr::AllDatabases();  // initialised before any fork
  for (uint32_t i = 0; i < info.shards; ++i) {
    ShardResult result = options.isolate ? CheckShardIsolated(dir, info, *settings, i, options.live, options.deadline)
                                         : CheckShard(dir, info, *settings, i, options.live);
    report.shards.push_back(result.report);
    for (VerifyProblem& p : result.problems) report.problems.push_back(std::move(p));
    for (std::string& n : result.notes) report.notes.push_back(std::move(n));
    if (result.deadline_exceeded) {
      report.deadline_exceeded = true;
      return report;
    }
  }
  if (with_log) VerifyLog(dir, options.live, report);
  return report;
}

}  // namespace

VerifyReport VerifyMap(const std::string& dir, const MapInfo& info, const VerifyOptions& options) {
  return Verify(dir, info, options, true);
}

VerifyReport VerifyShards(const std::string& dir, const MapInfo& info, const VerifyOptions& options) {
  return Verify(dir, info, options, false);
}

bool DataDirVerifyReport::clean() const {
  return problems.empty() && std::all_of(maps.begin(), maps.end(), [](const VerifyReport& m) { return m.clean(); });
}

DataDirVerifyReport VerifyDataDir(const std::string& data_dir, const VerifyOptions& options) {
  DataDirVerifyReport report;
  // No FORMAT file is no problem: the next store to open the directory writes it (data_dir_format.h).
  if (auto format = ReadDataDirFormat(Env::Default(), data_dir); !format.ok()) {
    report.problems.push_back({"FORMAT", "", std::string(format.status().message())});
  } else if (!ReadableDataDirFormat(*format)) {
    report.problems.push_back({"FORMAT", "", std::string(UnreadableFormatError(data_dir, *format).message())});
    return report;
  }
  auto catalog = Catalog::OpenReadOnly(data_dir + "/catalog");
  if (!catalog.ok()) {
    report.problems.push_back({"catalog/data.mdb", "", absl::StrCat("cannot be opened: ", catalog.status().message())});
    return report;
  }
  std::vector<MapInfo> maps;
  absl::flat_hash_set<uint64_t> ids;
  const absl::Status walked = (*catalog)->ForEachRecord([&](const std::string& name,
                                                            const absl::StatusOr<MapInfo>& info) {
    const std::string where = absl::StrCat("record of map \"", absl::CHexEscape(name), "\"");
    if (!info.ok()) {
      report.problems.push_back({"catalog/data.mdb", where, std::string(info.status().message())});
    } else if (info->name != name) {
      report.problems.push_back({"catalog/data.mdb", where, absl::StrCat("holds map \"", info->name, "\"")});
    } else if (!ids.insert(info->id).second) {
      report.problems.push_back({"catalog/data.mdb", where, absl::StrCat("id ", info->id, " is another map's too")});
    } else {
      maps.push_back(*info);
    }
  });
  if (!walked.ok()) {
    report.problems.push_back({"catalog/data.mdb", "", absl::StrCat("cannot be read to its end: ", walked.message())});
  }
  catalog->reset();
  // Directories the catalog does not name: a store opening this data directory reports them and leaves them.
  if (DIR* d = opendir((data_dir + "/maps").c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string entry = e->d_name;
      if (entry == "." || entry == "..") continue;
      uint64_t id = 0;
      const bool numeric = !entry.empty() && entry.size() <= 20 &&
                           std::all_of(entry.begin(), entry.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
                           std::sscanf(entry.c_str(), "%" SCNu64, &id) == 1 && std::to_string(id) == entry;
      if (!numeric || !ids.contains(id)) {
        report.problems.push_back(
            {absl::StrCat("maps/", entry), "", "a map directory the catalog does not name (a lost catalog record?)"});
      }
    }
    closedir(d);
  }
  for (const MapInfo& info : maps) {
    const std::string dir = MapDirIn(data_dir, info.id);
    struct stat st;
    if (stat(dir.c_str(), &st) != 0) {
      report.problems.push_back(
          {absl::StrCat("maps/", info.id), "", absl::StrCat("map \"", info.name, "\" has no directory")});
      continue;
    }
    report.maps.push_back(VerifyMap(dir, info, options));
  }
  return report;
}

std::string FormatProblem(const VerifyProblem& problem) {
  return problem.where.empty() ? absl::StrCat(problem.file, ": ", problem.what)
                               : absl::StrCat(problem.file, ": ", problem.where, ": ", problem.what);
}

}  // namespace fremen::storage
