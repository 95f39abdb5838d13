#include "storage/lmdb/lmdb_env.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstring>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "storage/lmdb/record_checksum.h"

namespace fremen::storage {

namespace {

// The internal database holding the record format marker (lmdb_env.h).
constexpr char kFormatDb[] = "fremen";
constexpr char kFormatKey[] = "record_format";

std::span<const uint8_t> Bytes(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

std::string Hex(std::span<const uint8_t> bytes) {
  return absl::BytesToHexString(absl::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace

absl::Status LmdbStatus(int rc, absl::string_view what) {
  if (rc == MDB_SUCCESS) return absl::OkStatus();
  const std::string message = absl::StrCat(what, ": ", mdb_strerror(rc));
  switch (rc) {
    case MDB_NOTFOUND:
      return absl::NotFoundError(message);
    case MDB_KEYEXIST:
      return absl::AlreadyExistsError(message);
    case MDB_CORRUPTED:
    case MDB_PAGE_NOTFOUND:
    case MDB_INVALID:
    case MDB_VERSION_MISMATCH:
      return absl::DataLossError(message);
    case MDB_MAP_FULL:
    case MDB_READERS_FULL:
    case MDB_TXN_FULL:
    case MDB_DBS_FULL:
    case ENOMEM:
    case ENOSPC:
      return absl::ResourceExhaustedError(message);
    case EACCES:
      return absl::PermissionDeniedError(message);
    default:
      return absl::InternalError(message);
  }
}

absl::StatusOr<MDB_dbi> LmdbTxn::Db(const std::string& name) const {
  const auto it = dbs_->find(name);
  if (it == dbs_->end() && absent_ != nullptr && std::find(absent_->begin(), absent_->end(), name) != absent_->end()) {
    return absl::NotFoundError(absl::StrCat("database ", name, " does not exist"));
  }
  if (it == dbs_->end()) return absl::InvalidArgumentError(absl::StrCat("database ", name, " was not declared"));
  return it->second;
}

absl::Status LmdbEnv::OpenDatabases(const std::vector<std::string>& names, bool read_only) {
  MDB_txn* txn;
  int rc = mdb_txn_begin(env_, nullptr, read_only ? MDB_RDONLY : 0, &txn);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_txn_begin");
  for (const std::string& name : names) {
    MDB_dbi dbi;
    rc = mdb_dbi_open(txn, name.c_str(), read_only ? 0 : MDB_CREATE, &dbi);
    if (rc == MDB_NOTFOUND && read_only) {
      absent_.push_back(name);
      continue;
    }
    if (rc != MDB_SUCCESS) {
      mdb_txn_abort(txn);
      return LmdbStatus(rc, absl::StrCat("mdb_dbi_open ", name, " in ", file_));
    }
    dbs_[name] = dbi;
  }
  LmdbTxn wrapped(txn, &dbs_, &file_, &absent_);
  if (absl::Status format = CheckRecordFormat(wrapped, read_only); !format.ok()) {
    mdb_txn_abort(txn);
    return format;
  }
  return LmdbStatus(mdb_txn_commit(txn), "mdb_txn_commit (databases)");
}

absl::Status LmdbEnv::CheckRecordFormat(LmdbTxn& txn, bool read_only) {
  MDB_dbi format_db;
  const int rc = mdb_dbi_open(txn.get(), kFormatDb, read_only ? 0 : MDB_CREATE, &format_db);
  const bool unmarked = read_only && rc == MDB_NOTFOUND;
  if (rc != MDB_SUCCESS && !unmarked) return LmdbStatus(rc, absl::StrCat("mdb_dbi_open ", kFormatDb, " in ", file_));
  auto marker = unmarked ? absl::StatusOr<std::span<const uint8_t>>(absl::NotFoundError("no marker"))
                         : txn.Get(format_db, Bytes(kFormatKey));
  if (marker.ok()) {
    if (marker->size() == 1 && (*marker)[0] == kLmdbRecordFormat) return absl::OkStatus();
    return absl::FailedPreconditionError(absl::StrCat(file_, " holds records of format ",
                                                      marker->size() == 1 ? (*marker)[0] : -1,
                                                      "; this build reads format ", kLmdbRecordFormat));
  }
  if (!absl::IsNotFound(marker.status())) return marker.status();
  // No marker: a new environment, or one written before records had checksums.
  for (const auto& [name, dbi] : dbs_) {
    auto count = txn.Count(dbi);
    if (!count.ok()) return count.status();
    if (*count > 0) {
      return absl::FailedPreconditionError(absl::StrCat(file_, " holds records without checksums (database ", name,
                                                        ", written by a fremen before record format ",
                                                        kLmdbRecordFormat, "); this build cannot read them"));
    }
  }
  if (read_only) return absl::OkStatus();  // empty: nothing to read, nothing to mark
  const uint8_t format = kLmdbRecordFormat;
  return txn.Put(format_db, Bytes(kFormatKey), {&format, 1});
}

absl::Status LmdbTxn::Put(MDB_dbi dbi, std::span<const uint8_t> key, std::span<const uint8_t> value, unsigned flags) {
  // MDB_RESERVE: LMDB makes room and the value and its checksum are written there, with no copy.
  MDB_val k = AsVal(key), v{value.size() + kRecordChecksumBytes, nullptr};
  const int rc = mdb_put(txn_, dbi, &k, &v, flags | MDB_RESERVE);
  if (rc == MDB_MAP_FULL) map_full_ = true;
  if (rc == MDB_SUCCESS) EncodeChecked(key, value, static_cast<uint8_t*>(v.mv_data));
  return LmdbStatus(rc, "mdb_put");
}

absl::StatusOr<std::span<const uint8_t>> LmdbTxn::Checked(MDB_dbi dbi, std::span<const uint8_t> key,
                                                          std::span<const uint8_t> stored) const {
  auto value = CheckRecord(key, stored);
  if (value.ok()) return value;
  std::string db = "?";
  for (const auto& [name, handle] : *dbs_) {
    if (handle == dbi) db = name;
  }
  return absl::DataLossError(
      absl::StrCat(*file_, ": database ", db, ", key ", Hex(key), ": ", value.status().message()));
}

absl::StatusOr<std::span<const uint8_t>> LmdbTxn::Get(MDB_dbi dbi, std::span<const uint8_t> key) const {
  MDB_val k = AsVal(key), v;
  const int rc = mdb_get(txn_, dbi, &k, &v);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, absl::StrCat("mdb_get ", *file_));
  return Checked(dbi, key, AsBytes(v));
}

absl::Status LmdbTxn::Delete(MDB_dbi dbi, std::span<const uint8_t> key) {
  MDB_val k = AsVal(key);
  const int rc = mdb_del(txn_, dbi, &k, nullptr);
  return rc == MDB_NOTFOUND ? absl::OkStatus() : LmdbStatus(rc, "mdb_del");
}

absl::Status LmdbTxn::Drop(MDB_dbi dbi) { return LmdbStatus(mdb_drop(txn_, dbi, 0), "mdb_drop"); }

absl::Status LmdbTxn::Scan(MDB_dbi dbi, std::span<const uint8_t> begin, std::span<const uint8_t> end,
                           const std::function<bool(std::span<const uint8_t>, std::span<const uint8_t>)>& f) const {
  absl::Status damaged;
  const absl::Status scanned = ScanChecked(dbi, begin, end, [&](auto key, auto value) {
    if (!value.ok()) {
      damaged = value.status();
      return false;
    }
    return f(key, *value);
  });
  return scanned.ok() ? damaged : scanned;
}

absl::Status LmdbTxn::ScanChecked(
    MDB_dbi dbi, std::span<const uint8_t> begin, std::span<const uint8_t> end,
    const std::function<bool(std::span<const uint8_t>, absl::StatusOr<std::span<const uint8_t>>)>& f) const {
  MDB_cursor* cursor;
  int rc = mdb_cursor_open(txn_, dbi, &cursor);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_cursor_open");
  MDB_val k = AsVal(begin), v;
  rc = mdb_cursor_get(cursor, &k, &v, begin.empty() ? MDB_FIRST : MDB_SET_RANGE);
  while (rc == MDB_SUCCESS) {
    const std::span<const uint8_t> key = AsBytes(k);
    if (!end.empty()) {
      const int cmp = std::memcmp(key.data(), end.data(), std::min(key.size(), end.size()));
      if (cmp > 0 || (cmp == 0 && key.size() >= end.size())) break;
    }
    if (!f(key, Checked(dbi, key, AsBytes(v)))) break;
    rc = mdb_cursor_get(cursor, &k, &v, MDB_NEXT);
  }
  mdb_cursor_close(cursor);
  return rc == MDB_SUCCESS || rc == MDB_NOTFOUND ? absl::OkStatus()
                                                 : LmdbStatus(rc, absl::StrCat("mdb_cursor_get ", *file_));
}

absl::StatusOr<size_t> LmdbTxn::Count(MDB_dbi dbi) const {
  MDB_stat stat;
  const int rc = mdb_stat(txn_, dbi, &stat);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_stat");
  return stat.ms_entries;
}

absl::StatusOr<std::unique_ptr<LmdbEnv>> LmdbEnv::Open(const std::string& dir, const LmdbOptions& options) {
  if (!options.read_only && mkdir(dir.c_str(), 0750) != 0 && errno != EEXIST) {
    return absl::InternalError(absl::StrCat("cannot create ", dir, ": ", std::strerror(errno)));
  }
  MDB_env* env;
  int rc = mdb_env_create(&env);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_env_create");
  mdb_env_set_maxdbs(env, options.max_dbs);
  mdb_env_set_maxreaders(env, options.max_readers);
  mdb_env_set_mapsize(env, options.initial_map_size);
  // NOTLS: read transactions are not tied to a thread (handlers may hop threads). NORDAHEAD: the
  // access pattern is random lookups or full scans into memory, where readahead only pollutes.
  unsigned flags = MDB_NOTLS | MDB_NORDAHEAD | (options.no_sync ? MDB_NOSYNC : 0);
  if (options.read_only) flags |= MDB_RDONLY | (options.no_lock ? MDB_NOLOCK : 0);
  rc = mdb_env_open(env, dir.c_str(), flags, 0640);
  if (rc != MDB_SUCCESS) {
    mdb_env_close(env);
    return LmdbStatus(rc, absl::StrCat("mdb_env_open ", dir));
  }
  MDB_envinfo info;
  mdb_env_info(env, &info);
  auto result = std::unique_ptr<LmdbEnv>(new LmdbEnv(env, dir, info.me_mapsize));
  result->read_only_ = options.read_only;
  int dead = 0;
  if (!options.no_lock) mdb_reader_check(env, &dead);  // slots of processes killed while reading
  if (absl::Status s = result->OpenDatabases(options.databases, options.read_only); !s.ok()) return s;
  return result;
}

LmdbEnv::~LmdbEnv() { mdb_env_close(env_); }

absl::Status LmdbEnv::health() const {
  base::MutexLock lock(&latch_mutex_);
  return latched_;
}

void LmdbEnv::Latch(const absl::Status& status) {
  base::MutexLock lock(&latch_mutex_);
  if (latched_.ok()) latched_ = status;
}

absl::Status LmdbEnv::Grow() {
  absl::MutexLock lock(&resize_);  // waits for every read transaction to end
  const size_t bigger = map_size_ * 2;
  const int rc = mdb_env_set_mapsize(env_, bigger);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_env_set_mapsize");
  map_size_ = bigger;
  growths_.fetch_add(1, std::memory_order_relaxed);
  return absl::OkStatus();
}

uint64_t LmdbEnv::readers() const {
  MDB_envinfo info;
  if (mdb_env_info(env_, &info) != MDB_SUCCESS) return 0;
  return info.me_numreaders;
}

absl::Status LmdbEnv::Write(const std::function<absl::Status(LmdbTxn&)>& f) {
  base::MutexLock writer(&writer_);
  if (read_only_) return absl::FailedPreconditionError(absl::StrCat(dir_, " is open for reading only"));
  if (absl::Status latched = health(); !latched.ok()) return latched;
  for (;;) {
    int rc;
    MDB_txn* txn = nullptr;
    {
      absl::ReaderMutexLock lock(&resize_);
      rc = mdb_txn_begin(env_, nullptr, 0, &txn);
      if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_txn_begin");
      LmdbTxn wrapped(txn, &dbs_, &file_);
      absl::Status status = f(wrapped);
      if (!status.ok()) {
        mdb_txn_abort(txn);
        if (!wrapped.map_full()) return status;
        rc = MDB_MAP_FULL;
      } else {
        rc = Commit(txn);
        if (rc == MDB_SUCCESS) return absl::OkStatus();
      }
    }
    if (rc != MDB_MAP_FULL) {
      // A failed commit may have left the data file behind the caller's belief: refuse later writes.
      absl::Status failed = LmdbStatus(rc, "mdb_txn_commit");
      Latch(failed);
      return failed;
    }
    if (absl::Status grown = Grow(); !grown.ok()) return grown;
  }
}

int LmdbEnv::Commit(MDB_txn* txn) {
  commits_started_.fetch_add(1);
  const int rc = mdb_txn_commit(txn);
  commits_ended_.fetch_add(1);
  return rc;
}

int LmdbEnv::BeginSnapshot(MDB_txn** txn) const {
  for (;;) {
    // Commits ended before the begin: the snapshot chosen is at least the last of them, T, and T's
    // meta page is next written by the second commit after it.
    const uint64_t ended = commits_ended_.load();
    const int rc = mdb_txn_begin(env_, nullptr, MDB_RDONLY, txn);
    if (rc != MDB_SUCCESS) return rc;
    std::atomic_thread_fence(std::memory_order_seq_cst);  // the page copy above comes before this load
    if (commits_started_.load() - ended < 2) return MDB_SUCCESS;
    mdb_txn_abort(*txn);
  }
}

absl::Status LmdbEnv::Read(const std::function<absl::Status(LmdbTxn&)>& f) const {
  absl::ReaderMutexLock lock(&resize_);
  MDB_txn* txn;
  const int rc = BeginSnapshot(&txn);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_txn_begin (read)");
  LmdbTxn wrapped(txn, &dbs_, &file_, &absent_);
  absl::Status status = f(wrapped);
  mdb_txn_abort(txn);
  return status;
}

absl::Status LmdbEnv::Sync() {
  absl::Status status = LmdbStatus(mdb_env_sync(env_, 1), "mdb_env_sync");
  if (!status.ok()) Latch(status);
  return status;
}

absl::StatusOr<int> LmdbEnv::ClearStaleReaders() {
  int dead = 0;
  const int rc = mdb_reader_check(env_, &dead);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_reader_check");
  return dead;
}

absl::Status LmdbEnv::CopyTo(const std::string& dir) const {
  if (mkdir(dir.c_str(), 0750) != 0 && errno != EEXIST) {
    return absl::InternalError(absl::StrCat("cannot create ", dir, ": ", std::strerror(errno)));
  }
  absl::ReaderMutexLock lock(&resize_);
  return LmdbStatus(mdb_env_copy2(env_, dir.c_str(), MDB_CP_COMPACT), absl::StrCat("mdb_env_copy2 ", dir));
}

absl::StatusOr<size_t> LmdbEnv::UsedBytes() const {
  MDB_envinfo info;
  MDB_stat stat;
  int rc = mdb_env_info(env_, &info);
  if (rc == MDB_SUCCESS) rc = mdb_env_stat(env_, &stat);
  if (rc != MDB_SUCCESS) return LmdbStatus(rc, "mdb_env_info");
  return (info.me_last_pgno + 1) * static_cast<size_t>(stat.ms_psize);
}

}  // namespace fremen::storage
