#include "storage/salvage.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "storage/batch.h"
#include "storage/catalog.h"
#include "storage/cell_key.h"
#include "storage/dedup_table.h"
#include "storage/isolated_child.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/model/varint.h"
#include "storage/shard_record_checks.h"
#include "storage/shard_records.h"
#include "storage/static_bricks.h"
#include "storage/store.h"
#include "storage/wal/wal.h"

namespace fremen::storage {

uint64_t SalvageShard::kept() const {
  uint64_t n = 0;
  for (const SalvageDatabase& d : databases) n += d.kept;
  return n;
}

uint64_t SalvageShard::lost() const {
  uint64_t n = 0;
  for (const SalvageDatabase& d : databases) n += d.lost;
  return n;
}

uint64_t SalvageReport::records_kept() const {
  uint64_t n = 0;
  for (const SalvageShard& s : shards) n += s.kept();
  return n;
}

uint64_t SalvageReport::records_lost() const {
  uint64_t n = 0;
  for (const SalvageShard& s : shards) n += s.lost();
  return n;
}

namespace {

namespace sr = shard_records;
namespace fs = std::filesystem;

// The first byte of a log record (storage/map_store.cc).
constexpr uint8_t kBatchRecord = 'B';
constexpr uint8_t kPublishRecord = 'P';

// A record that belongs to a dynamic state's record, as the salvage report names it.
const char* AttachedRecordName(const std::string& db) {
  return db == sr::kPublishedDb ? "a published model" : db == sr::kWideDb ? "a wide body" : "a lossless history";
}
// The log's record header (storage/wal/wal.h).
constexpr uint64_t kLogRecordHeader = 16;
// Records written to a new shard per LMDB transaction.
constexpr size_t kRecordsPerTxn = 4096;

std::string ShardFile(uint32_t shard) { return absl::StrCat("shard-", shard, "/data.mdb"); }
std::string_view View(std::span<const uint8_t> b) { return {reinterpret_cast<const char*>(b.data()), b.size()}; }
std::span<const uint8_t> Bytes(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

// --- what a reading child sends: frames of u32 length | tag | fields ---

enum Tag : uint8_t {
  kCount = 'N',    // varint: the records the database holds (LMDB's count, no value read)
  kRecord = 'R',   // key, value (without its checksum)
  kDamaged = 'D',  // key, what: a record whose checksum fails
  kStopped = 'E',  // what: the scan could not go on (the rest of the database was not read)
  kEnd = 'Z',      // the database was read to its end
};

void PutString(std::string& out, std::string_view s) {
  model::PutVarint64(&out, s.size());
  out += s;
}

bool SendFrame(int fd, Tag tag, std::string_view a = {}, std::string_view b = {}) {
  std::string body(1, static_cast<char>(tag));
  PutString(body, a);
  PutString(body, b);
  std::string frame(4, '\0');
  model::EncodeFixed32(frame.data(), static_cast<uint32_t>(body.size()));
  frame += body;
  return WriteAll(fd, frame);
}

// In the child: every record of one database, each sent as soon as it is read, so that what LMDB
// read before an abort reaches the parent.
bool SendDatabase(int fd, const std::string& shard_dir, const std::string& db_name) {
  struct stat st;
  if (stat((shard_dir + "/data.mdb").c_str(), &st) != 0) return SendFrame(fd, kStopped, "the file cannot be read");
  LmdbOptions options;
  options.read_only = true;
  options.no_lock = true;  // a failed map is not open: the files are at rest
  options.databases = sr::AllDatabases();
  options.initial_map_size = std::max<size_t>(options.initial_map_size, static_cast<size_t>(st.st_size));
  auto env = LmdbEnv::Open(shard_dir, options);
  if (!env.ok()) return SendFrame(fd, kStopped, absl::StrCat("cannot be opened: ", env.status().message()));
  bool sent = true;
  const absl::Status read = (*env)->Read([&](LmdbTxn& txn) -> absl::Status {
    auto db = txn.Db(db_name);
    if (absl::IsNotFound(db.status())) return absl::OkStatus();  // never written: nothing to salvage
    if (!db.ok()) return db.status();
    if (auto count = txn.Count(*db); count.ok()) sent = SendFrame(fd, kCount, std::to_string(*count));
    return txn.ScanChecked(*db, {}, {}, [&](auto key, auto checked) {
      sent = checked.ok() ? SendFrame(fd, kRecord, View(key), View(*checked))
                          : SendFrame(fd, kDamaged, View(key), std::string(checked.status().message()));
      return sent;
    });
  });
  if (!sent) return false;
  return read.ok() ? SendFrame(fd, kEnd) : SendFrame(fd, kStopped, std::string(read.message()));
}

// A damaged map's records, one database at a time, into the new shard.
class ShardSalvager {
 public:
  ShardSalvager(const MapInfo& info, const model::ModelSettings& settings, uint32_t shard, absl::Time deadline,
                SalvageReport& report)
      : shard_(shard), deadline_(deadline), checks_(info, settings, shard), report_(report) {
    shard_report_.shard = shard;
  }

  // Reads the damaged shard in `from_dir` into the new environment at `to_dir` (meta records last,
  // by WriteMeta once the log has been salvaged).
  absl::Status Run(const std::string& from_dir, const std::string& to_dir) {
    LmdbOptions options;
    options.no_sync = true;  // synced once, by WriteMeta
    options.databases = sr::AllDatabases();
    auto env = LmdbEnv::Open(to_dir, options);
    if (!env.ok()) return env.status();
    env_ = *std::move(env);
    for (const std::string& db : sr::AllDatabases()) shard_report_.databases.push_back({db, 0, 0});
    // The meta records first: the checkpoint LSN decides what the log replays, and the touched
    // list is filtered by the states that survive.
    for (const std::string db :
         {sr::kMetaDb, sr::kStaticDb, sr::kDynamicDb, sr::kPublishedDb, sr::kLosslessDb, sr::kWideDb, sr::kLabelsDb}) {
      ReadDatabase(from_dir, db);
      if (!write_error_.ok()) return write_error_;
      if (db == sr::kDynamicDb) WriteStatic();
      if (!write_error_.ok()) return write_error_;
    }
    return absl::OkStatus();
  }

  // The checkpoint LSN read, when it was; nullopt when it was lost (damaged or not read). A shard
  // never checkpointed has 0.
  std::optional<uint64_t> checkpoint_lsn() const {
    if (lsn_lost_) return std::nullopt;
    return checkpoint_lsn_;
  }

  // Writes the meta records with the checkpoint LSN the salvage settled on, syncs and closes.
  absl::Status WriteMeta(uint64_t checkpoint_lsn) {
    std::vector<uint64_t> touched;
    if (touched_) {
      for (uint64_t k : *touched_) {
        if (dynamic_keys_.contains(k)) touched.push_back(k);
      }
    }
    const std::string touched_bytes = sr::EncodeTouched(touched);
    absl::Status written = env_->Write([&](LmdbTxn& txn) -> absl::Status {
      auto meta = txn.Db(sr::kMetaDb);
      if (!meta.ok()) return meta.status();
      if (checkpoint_lsn > 0 || had_lsn_record_) {
        uint8_t lsn[8];
        std::memcpy(lsn, &checkpoint_lsn, 8);  // host order, as the shard writes it
        if (absl::Status s = txn.Put(*meta, Bytes(sr::kLsnKey), {lsn, 8}); !s.ok()) return s;
      }
      if (touched_) {
        if (absl::Status s = txn.Put(*meta, Bytes(sr::kTouchedKey), Bytes(touched_bytes)); !s.ok()) return s;
      }
      for (const auto& [name, value] : other_meta_) {
        if (absl::Status s = txn.Put(*meta, Bytes(name), Bytes(value)); !s.ok()) return s;
      }
      return absl::OkStatus();
    });
    if (written.ok()) written = env_->Sync();
    env_.reset();  // one environment per file per process: the map's open comes next
    return written;
  }

  SalvageShard report() const { return shard_report_; }

 private:
  SalvageDatabase& Counts(const std::string& db) {
    for (SalvageDatabase& d : shard_report_.databases) {
      if (d.name == db) return d;
    }
    return shard_report_.databases.front();  // every name is there (Run)
  }

  void Lost(const std::string& db, std::string where, std::string what, uint64_t records = 1) {
    Counts(db).lost += records;
    ++report_.losses;
    if (report_.lost.size() < kMaxListedLosses) {
      report_.lost.push_back({ShardFile(shard_), std::move(where), std::move(what)});
    }
  }

  void ReadDatabase(const std::string& from_dir, const std::string& db) {
    const std::string shard_dir = absl::StrCat(from_dir, "/shard-", shard_);
    std::string buffer;
    std::optional<uint64_t> count;
    uint64_t received = 0;  // records, good or damaged
    std::optional<uint64_t> last_key;
    bool ended = false;
    const auto on_frame = [&](std::string_view frame) {
      model::ByteReader r(frame, "salvage child frame");
      const uint8_t tag = r.Byte("tag");
      const std::string_view a = r.Bytes(r.Varint("length"), "first field");
      const std::string_view b = r.Bytes(r.Varint("length"), "second field");
      if (!r.Finish().ok()) return;
      switch (tag) {
        case kCount:
          if (uint64_t n = 0; absl::SimpleAtoi(absl::string_view(a.data(), a.size()), &n)) count = n;
          break;
        case kRecord:
          ++received;
          if (a.size() == 8) last_key = KeyFromBytes(reinterpret_cast<const uint8_t*>(a.data()));
          Take(db, a, b);
          break;
        case kDamaged:
          ++received;
          if (a.size() == 8) last_key = KeyFromBytes(reinterpret_cast<const uint8_t*>(a.data()));
          if (db == sr::kMetaDb && a == sr::kLsnKey) lsn_lost_ = true;
          Lost(db, absl::StrCat(db, " record #", received), std::string(b));
          break;
        case kStopped:
          ended = true;
          LostRest(db, last_key, std::string(b), count, received);
          break;
        case kEnd:
          ended = true;
          break;
      }
    };
    auto exit = RunIsolated([&](int fd) { return SendDatabase(fd, shard_dir, db); },
                            [&](std::string_view chunk) {
                              buffer.append(chunk);
                              size_t pos = 0;
                              while (buffer.size() - pos >= 4) {
                                const uint32_t n = model::DecodeFixed32(buffer.data() + pos);
                                if (buffer.size() - pos - 4 < n) break;
                                on_frame(std::string_view(buffer).substr(pos + 4, n));
                                pos += 4 + n;
                              }
                              buffer.erase(0, pos);
                            },
                            deadline_);
    if (absl::IsDeadlineExceeded(exit.status())) {
      // Not a loss of the damaged map: the salvage is not finished, and no map is made of half of it.
      write_error_ = absl::DeadlineExceededError(
          absl::StrCat("the salvage did not finish by its deadline, at ", ShardFile(shard_), " ", db, ": ",
                       exit.status().message()));
      return;
    }
    Flush();
    // The LSN's record was not among those read before the meta database stopped, or (below) a damaged record whose
    // key may have been it: what the shard holds of the log is unknown.
    if (db == sr::kMetaDb && !ended && !had_lsn_record_) lsn_lost_ = true;
    if (db == sr::kMetaDb && ended && !had_lsn_record_ && Counts(db).lost > 0) lsn_lost_ = true;
    if (!exit.ok()) {
      LostRest(db, last_key, absl::StrCat("not read: ", exit.status().message()), count, received);
    } else if (!ended) {
      LostRest(db, last_key, DescribeChildExit(*exit), count, received);
    }
  }

  // The database could not be read past `last_key`: what LMDB counted and was not received is lost.
  void LostRest(const std::string& db, std::optional<uint64_t> last_key, std::string why, std::optional<uint64_t> count,
                uint64_t received) {
    const uint64_t rest = count && *count > received ? *count - received : 0;
    Lost(db, last_key ? absl::StrCat(db, " after key ", *last_key) : std::string(db),
         absl::StrCat(why, "; the rest of this database was lost (",
                      count ? absl::StrCat(rest, " records") : std::string("an unknown number of records"), ")"),
         rest);
  }

  // A record read intact: kept when it passes its checks.
  void Take(const std::string& db, std::string_view key, std::string_view value) {
    if (db == sr::kMetaDb) return TakeMeta(key, value);
    if (key.size() != 8) {
      return Lost(db, absl::StrCat(db, " record of a ", key.size(), "-byte key"),
                  absl::StrCat("a key of ", key.size(), " bytes, not 8"));
    }
    const uint64_t k = KeyFromBytes(reinterpret_cast<const uint8_t*>(key.data()));
    const std::string where = absl::StrCat(db, " record of key ", k);
    absl::Status checked;
    if (db == sr::kStaticDb) {
      StaticBrick brick;
      checked = checks_.Static(k, value, &brick);
      if (checked.ok()) {
        static_[k] = std::move(brick);
        return;  // written by WriteStatic, once the changed states are known
      }
    } else if (db == sr::kDynamicDb) {
      checked = checks_.Dynamic(k, value);
      if (checked.ok()) dynamic_keys_.insert(k);
    } else if (db == sr::kPublishedDb || db == sr::kLosslessDb || db == sr::kWideDb) {
      if (!dynamic_keys_.contains(k)) {
        checked = absl::DataLossError(absl::StrCat(AttachedRecordName(db), " without its state (its record was lost)"));
      } else {
        checked = db == sr::kPublishedDb ? checks_.Published(value)
                  : db == sr::kWideDb    ? checks_.Wide(value)
                                         : checks_.Lossless(value);
      }
    } else if (db == sr::kLabelsDb) {
      checked = checks_.Label(k, value);
    }
    if (!checked.ok()) return Lost(db, where, std::string(checked.message()));
    pending_.push_back({std::string(db), std::string(key), std::string(value)});
    ++Counts(db).kept;
    if (pending_.size() >= kRecordsPerTxn) Flush();
  }

  void TakeMeta(std::string_view name, std::string_view value) {
    const std::string where =
        absl::StrCat("meta record ", absl::CHexEscape(absl::string_view(name.data(), name.size())));
    if (name == sr::kLsnKey) {
      had_lsn_record_ = true;
      auto lsn = sr::DecodeCheckpointLsn(Bytes(value));
      if (!lsn.ok()) {
        lsn_lost_ = true;
        return Lost(sr::kMetaDb, where, std::string(lsn.status().message()));
      }
      checkpoint_lsn_ = *lsn;
    } else if (name == sr::kTouchedKey) {
      auto keys = sr::DecodeTouched(value);
      if (!keys.ok()) return Lost(sr::kMetaDb, where, std::string(keys.status().message()));
      touched_ = *std::move(keys);
    } else if (name == sr::kDedupKey) {
      if (auto table = DedupTable::Decode(value); !table.ok()) {
        return Lost(sr::kMetaDb, where, std::string(table.status().message()));
      }
      other_meta_.emplace_back(name, value);
    } else {
      other_meta_.emplace_back(name, value);  // not one this version knows: kept as it verified
    }
    ++Counts(sr::kMetaDb).kept;
  }

  // The never-changed bricks, less any state that is also stored as changed (the changed model is
  // the newer: a state is promoted, never demoted).
  void WriteStatic() {
    for (auto& entry : static_) {
      // A named copy, not a structured binding: clang 14 does not let a lambda capture those.
      const uint64_t brick_key = entry.first;
      auto& brick = entry.second;
      StaticBrick kept;
      brick.ForEach([&](uint32_t i, const model::StaticState& state) {
        const uint64_t key = brick_key << kBrickBits | i;
        if (dynamic_keys_.contains(key)) {
          ++report_.losses;
          if (report_.lost.size() < kMaxListedLosses) {
            report_.lost.push_back(
                {ShardFile(shard_), absl::StrCat("static record of key ", brick_key),
                 absl::StrCat("state ", key, " is also stored as changed: its never-changed copy was dropped")});
          }
          return;
        }
        kept.Add(i, state);
      });
      if (kept.empty()) {
        ++Counts(sr::kStaticDb).lost;
        continue;
      }
      const auto key = KeyBytes(brick_key);
      pending_.push_back({sr::kStaticDb, std::string(key.begin(), key.end()), kept.Encode()});
      ++Counts(sr::kStaticDb).kept;
      if (pending_.size() >= kRecordsPerTxn) Flush();
    }
    static_.clear();
    Flush();
  }

  void Flush() {
    if (pending_.empty() || !write_error_.ok()) return;
    write_error_ = env_->Write([&](LmdbTxn& txn) -> absl::Status {
      for (const Pending& p : pending_) {
        auto db = txn.Db(p.db);
        if (!db.ok()) return db.status();
        if (absl::Status s = txn.Put(*db, Bytes(p.key), Bytes(p.value)); !s.ok()) return s;
      }
      return absl::OkStatus();
    });
    pending_.clear();
  }

  struct Pending {
    std::string db, key, value;
  };

  const uint32_t shard_;
  const absl::Time deadline_;
  const ShardRecordChecks checks_;
  SalvageReport& report_;
  SalvageShard shard_report_;
  std::unique_ptr<LmdbEnv> env_;
  absl::Status write_error_;
  std::vector<Pending> pending_;
  std::map<uint64_t, StaticBrick> static_;
  absl::flat_hash_set<uint64_t> dynamic_keys_;
  uint64_t checkpoint_lsn_ = 0;  // 0: never checkpointed (no record)
  bool had_lsn_record_ = false;
  // The checkpoint LSN's record was damaged, or the meta database was not read as far as it.
  bool lsn_lost_ = false;
  std::optional<std::vector<uint64_t>> touched_;
  std::vector<std::pair<std::string, std::string>> other_meta_;
};

// Copies the intact prefix of the damaged log into `to_wal`, under the same LSNs.
absl::Status SalvageLogRecords(const std::string& from_wal, const std::string& to_wal, uint64_t after_lsn,
                               const StoreOptions& options, SalvageReport& report) {
  std::unique_ptr<WalWriter> writer;
  absl::Status write_error;
  const auto open_at = [&](uint64_t lsn) -> absl::Status {
    if (writer) {
      if (absl::Status s = writer->Sync(); !s.ok()) return s;
      writer.reset();
    }
    WalOptions wal_options;
    wal_options.segment_bytes = options.log_segment_bytes;
    wal_options.env = options.env;
    wal_options.min_next_lsn = lsn;
    auto opened = WalWriter::Open(to_wal, wal_options);
    if (!opened.ok()) return opened.status();
    writer = *std::move(opened);
    return absl::OkStatus();
  };
  SalvageLog& log = report.log;
  std::error_code error;
  if (!fs::exists(from_wal, error)) return absl::OkStatus();  // no log: nothing to replay (and nothing lost)
  WalStop stop;
  auto replayed = ReplayWal(
      from_wal, after_lsn,
      [&](uint64_t lsn, std::span<const uint8_t> payload) -> absl::Status {
        const bool publish = payload.size() == 1 && payload[0] == kPublishRecord;
        if (!publish) {
          if (payload.empty() || payload[0] != kBatchRecord) {
            return absl::DataLossError(absl::StrCat("log record ", lsn, ": unknown record kind"));
          }
          if (auto batch = DecodeBatch(View(payload.subspan(1))); !batch.ok()) {
            return absl::DataLossError(absl::StrCat("log record ", lsn, ": ", batch.status().message()));
          }
        }
        // A gap (below a checkpoint, where replay accepts it) starts a new segment, as the
        // recovery that made it did.
        if (!writer || writer->last_lsn() + 1 != lsn) {
          if (absl::Status s = open_at(lsn); !s.ok()) return write_error = s;
        }
        if (writer->Append(payload) != lsn) return write_error = absl::InternalError("salvaged log: LSN out of step");
        ++log.records_kept;
        log.bytes_kept += kLogRecordHeader + payload.size();
        log.last_lsn = lsn;
        if (log.records_kept % 1024 == 0) {
          if (absl::Status s = writer->Sync(); !s.ok()) return write_error = s;
        }
        return absl::OkStatus();
      },
      options.env, &stop);
  if (!write_error.ok()) return write_error;
  if (writer) {
    if (absl::Status s = writer->Sync(); !s.ok()) return s;
  }
  if (replayed.ok()) {
    log.last_lsn = std::max(log.last_lsn, replayed->last_lsn);
    if (replayed->truncated_tail) log.torn_tail_bytes = replayed->torn_tail_bytes;
    return absl::OkStatus();
  }
  // Without a place (the log could not be listed or read) nothing of it is kept, and what is lost is unknown.
  const bool placed = !stop.file.empty() && stop.lsn > 0;
  log.bytes_lost = stop.bytes_after;
  log.records_lost = !placed ? 0 : stop.highest_lsn_after >= stop.lsn ? stop.highest_lsn_after - stop.lsn + 1 : 1;
  if (log.last_lsn == 0 && placed) log.last_lsn = std::max(after_lsn, stop.lsn - 1);
  ++report.losses;
  if (report.lost.size() < kMaxListedLosses) {
    const std::string file = placed ? absl::StrCat("wal/", fs::path(stop.file).filename().string()) : "wal";
    report.lost.push_back({file, placed ? absl::StrCat("byte ", stop.offset, " (after LSN ", stop.lsn - 1, ")") : "",
                           absl::StrCat(replayed.status().message(), "; ", log.bytes_lost, " bytes (", log.records_lost,
                                        " records) from there on were lost")});
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<SalvageReport> SalvageFiles(const std::string& from_dir, const std::string& to_dir, const MapInfo& info,
                                           const StoreOptions& options, absl::Time deadline) {
  auto settings = ModelSettingsOf(info);
  if (!settings.ok()) return settings.status();
  SalvageReport report;
  report.map = info;
  report.from = info.name;
  (void)sr::AllDatabases();  // initialised before any fork
  std::vector<std::unique_ptr<ShardSalvager>> shards;
  for (uint32_t i = 0; i < info.shards; ++i) {
    shards.push_back(std::make_unique<ShardSalvager>(info, *settings, i, deadline, report));
    if (absl::Status s = shards.back()->Run(from_dir, absl::StrCat(to_dir, "/shard-", i)); !s.ok()) {
      return absl::Status(s.code(), absl::StrCat(to_dir, "/shard-", i, ": ", s.message()));
    }
  }
  // The log replays after the oldest checkpoint that is known.
  std::optional<uint64_t> oldest, newest;
  for (const auto& shard : shards) {
    if (const auto lsn = shard->checkpoint_lsn()) {
      oldest = std::min(oldest.value_or(UINT64_MAX), *lsn);
      newest = std::max(newest.value_or(0), *lsn);
    }
  }
  if (absl::Status s = SalvageLogRecords(from_dir + "/wal", to_dir + "/wal", oldest.value_or(0), options, report);
      !s.ok()) {
    return absl::Status(s.code(), absl::StrCat(to_dir, "/wal: ", s.message()));
  }
  const uint64_t log_end = report.log.last_lsn;
  // A shard whose checkpoint was lost may hold any record of the log: none is applied to it again.
  uint64_t floor = newest.value_or(0);
  bool any_lost = false;
  for (const auto& shard : shards) any_lost |= !shard->checkpoint_lsn().has_value();
  if (any_lost) floor = std::max(floor, log_end);
  for (uint32_t i = 0; i < shards.size(); ++i) {
    const std::optional<uint64_t> lsn = shards[i]->checkpoint_lsn();
    uint64_t settled = lsn.value_or(floor);
    if (!lsn) {
      ++report.losses;
      if (report.lost.size() < kMaxListedLosses) {
        report.lost.push_back({ShardFile(i), "meta record checkpoint_lsn",
                               absl::StrCat("the checkpoint LSN was lost; set to ", settled,
                                            ": no log record up to it is applied to this shard")});
      }
    } else if (settled < floor && log_end < floor) {
      // The records this shard lacks up to the newest checkpoint are gone with the log's tail.
      ++report.losses;
      if (report.lost.size() < kMaxListedLosses) {
        report.lost.push_back(
            {ShardFile(i), "meta record checkpoint_lsn",
             absl::StrCat("checkpoint LSN raised from ", settled, " to ", floor, ": the log ends at LSN ", log_end,
                          ", so records ", settled + 1, "..", floor, " are not applied to this shard")});
      }
      settled = floor;
    }
    if (absl::Status s = shards[i]->WriteMeta(settled); !s.ok()) {
      return absl::Status(
          s.code(), absl::StrCat(to_dir, "/shard-", i, ": ", s.message()));
    }
    report.shards.push_back(shards[i]->report());
  }
  return report;
}

}  // namespace fremen::storage

namespace fremen::storage {

absl::StatusOr<SalvageReport> Store::SalvageMap(const std::string& name, const std::string& new_name,
                                                absl::Time deadline) {
  const std::string target_name = new_name.empty() ? name + "-salvaged" : new_name;
  base::MutexLock lock(&mutex_);
  const auto failed = failed_.find(name);
  if (failed == failed_.end()) {
    if (maps_.contains(name)) {
      return absl::FailedPreconditionError(
          absl::StrCat("map ", name, " is not damaged; use BackupMap/RestoreMap to copy it"));
    }
    return absl::NotFoundError(absl::StrCat("no map named \"", name, "\""));
  }
  if (failed->second.id == 0) {
    return absl::FailedPreconditionError(absl::StrCat("map ", name,
                                                      ": its catalog record is damaged, so nothing says what its files "
                                                      "hold or where they are; it cannot be salvaged"));
  }
  if (salvaging_.contains(name)) {
    return absl::FailedPreconditionError(absl::StrCat("map ", name, " is being salvaged already"));
  }
  auto info = catalog_->Get(name);
  if (!info.ok()) return info.status();
  if (maps_.contains(target_name) || failed_.contains(target_name) || catalog_->Get(target_name).ok()) {
    return absl::AlreadyExistsError(absl::StrCat("new_map: a map named \"", target_name, "\" exists"));
  }
  MapInfo copy = *info;
  copy.name = target_name;
  auto created = catalog_->Create(copy, copy.shards, [this](uint64_t id) { return HasDirectory(id); });
  if (!created.ok()) return created.status();
  // Both names are held (DeleteMap refuses them, Map answers Unavailable for the new one) while the files are read and
  // written without the lock, so that the other maps serve meanwhile.
  const std::string from_dir = failed->second.dir;
  salvaging_.insert(name);
  salvaging_.insert(target_name);
  mutex_.Unlock();
  // The id has no directory (Create skipped those that do): everything under `target` is this call's, and only that is
  // removed when the salvage fails.
  const std::string target = MapDir(created->id);
  absl::StatusOr<SalvageReport> report;
  std::error_code error;
  fs::create_directories(target, error);
  if (error) {
    report = absl::InternalError(absl::StrCat(target, ": ", error.message()));
  } else {
    report = SalvageFiles(from_dir, target, *created, options_, deadline);
  }
  mutex_.Lock();
  salvaging_.erase(name);
  salvaging_.erase(target_name);
  if (report.ok()) {
    report->from = name;
    if (auto map = OpenMap(*created); !map.ok()) {
      report = absl::Status(map.status().code(),
                            absl::StrCat("the salvaged copy did not open, and was removed: ", map.status().message()));
    }
  }
  if (!report.ok()) {
    report = absl::Status(report.status().code(), absl::StrCat("salvage of map ", name, " into ", target_name, ": ",
                                                               report.status().message()));
    (void)catalog_->Delete(created->name);
    std::error_code ignored;
    fs::remove_all(target, ignored);
  }
  return report;
}

}  // namespace fremen::storage
