// A thin, safe wrapper over one LMDB environment (one directory, one data file).
//
// What it adds to LMDB (see lmdb.h):
// - every return code becomes an absl::Status in one place (LmdbStatus), MDB_CORRUPTED and MDB_PAGE_NOTFOUND as
//   DataLoss, MDB_MAP_FULL as ResourceExhausted;
// - write transactions that hit MDB_MAP_FULL are aborted, the map is grown (doubled, while no transaction of this
//   process is active) and the transaction is run again — so callers write a function that can be retried, never a
//   half-applied one;
// - stale reader slots of dead processes are cleared at open and on demand (mdb_reader_check);
// - a failed commit/sync latches the environment: every later write fails with the first error (the leveldb bg_error_
//   pattern) instead of pretending data is durable;
// - every record carries a checksum of its key and value (record_checksum.h): Put appends it, Get and Scan check it and
//   hand back the value without it; a mismatch is DataLoss naming the file (<dir>/data.mdb), the database and the key
//   (hex). Nothing reads or writes values past this.
//
// Record format: an environment records the format of its records (internal database "fremen", key "record_format").
// Format 1: value + checksum trailer. Files written before checksums (format 0, no marker but records) are refused at
// Open (FailedPrecondition) rather than read as damaged.
//
// Thread-safety: one writer at a time (Write serialises writers); any number of concurrent readers (Read). Read
// transactions are short: they hold a shared lock that map growth waits for.
#pragma once

#include <lmdb.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/synchronization/mutex.h"
#include "base/mutex.h"

namespace fremen::storage {

// Converts an LMDB return code; `what` names the operation ("mdb_put spectra").
absl::Status LmdbStatus(int rc, absl::string_view what);

struct LmdbOptions {
  // Initial map size in bytes; doubled whenever a write runs out of space. Small values are fine
  // (the map grows), large ones only reserve address space. Default: 64 MiB.
  size_t initial_map_size = 64ull << 20;
  // Named databases the environment may hold. Default: 16.
  unsigned max_dbs = 16;
  // Reader slots (concurrent read transactions across processes). Default: 126 (LMDB's default).
  unsigned max_readers = 126;
  // Skip fsync at commit: for files written in many transactions and synced once with Sync() before
  // anything depends on them (a salvage writes the new shards so, storage/salvage.h). Default: false.
  bool no_sync = false;
  // The named databases used in this environment. They are created (when missing) and their
  // handles opened once, at Open: LMDB forbids opening handles in concurrent transactions.
  std::vector<std::string> databases;
  // Open for reading only (MDB_RDONLY): the directory is not created, Write fails, and a declared
  // database the file does not hold is NotFound from LmdbTxn::Db. For checkers (storage/verify.h).
  // Default: false.
  bool read_only = false;
  // With read_only: no lock file is used or created (MDB_NOLOCK), so a backup directory is left
  // exactly as it is. Only when no process writes the file meanwhile. Default: false.
  bool no_lock = false;
};

// A byte view of an LMDB value, valid until its transaction ends.
inline std::span<const uint8_t> AsBytes(const MDB_val& v) {
  return {static_cast<const uint8_t*>(v.mv_data), v.mv_size};
}
inline MDB_val AsVal(std::span<const uint8_t> bytes) { return {bytes.size(), const_cast<uint8_t*>(bytes.data())}; }

using DbHandles = absl::flat_hash_map<std::string, MDB_dbi>;

// The record format this build writes and reads (see above).
inline constexpr uint8_t kLmdbRecordFormat = 1;

class LmdbTxn {
 public:
  // `file` names the environment's data file in errors; `absent`: the declared databases a
  // read-only environment does not hold.
  LmdbTxn(MDB_txn* txn, const DbHandles* dbs, const std::string* file,
          const std::vector<std::string>* absent = nullptr)
      : txn_(txn), dbs_(dbs), file_(file), absent_(absent) {}
  MDB_txn* get() const { return txn_; }

  // A database declared in LmdbOptions::databases; InvalidArgument for an undeclared name, NotFound
  // for one a read-only environment does not hold.
  absl::StatusOr<MDB_dbi> Db(const std::string& name) const;
  // Stores value with its checksum. `flags` as mdb_put's (MDB_NOOVERWRITE); MDB_RESERVE is implied.
  absl::Status Put(MDB_dbi dbi, std::span<const uint8_t> key, std::span<const uint8_t> value, unsigned flags = 0);
  // NotFound when absent, DataLoss when the checksum does not match; the view (without the checksum) is valid until the
  // transaction ends.
  absl::StatusOr<std::span<const uint8_t>> Get(MDB_dbi dbi, std::span<const uint8_t> key) const;
  // OK whether or not the key existed.
  absl::Status Delete(MDB_dbi dbi, std::span<const uint8_t> key);
  absl::Status Drop(MDB_dbi dbi);
  // Calls f(key, value) for keys in [begin, end) in key order (end empty: to the last key) until f returns false. A
  // record whose checksum does not match ends the scan with DataLoss.
  absl::Status Scan(MDB_dbi dbi, std::span<const uint8_t> begin, std::span<const uint8_t> end,
                    const std::function<bool(std::span<const uint8_t>, std::span<const uint8_t>)>& f) const;
  // As Scan, but a damaged record is handed to f as its DataLoss (naming file, database and key) and the scan goes on:
  // for callers that report damaged records and keep the others.
  absl::Status ScanChecked(
      MDB_dbi dbi, std::span<const uint8_t> begin, std::span<const uint8_t> end,
      const std::function<bool(std::span<const uint8_t>, absl::StatusOr<std::span<const uint8_t>>)>& f) const;
  // Records in the database (no value is read, so none is checked).
  absl::StatusOr<size_t> Count(MDB_dbi dbi) const;

  // Whether a put ran out of map space (LmdbEnv::Write then grows the map and retries).
  bool map_full() const { return map_full_; }

 private:
  // The value of a stored record, or DataLoss naming file, database and key.
  absl::StatusOr<std::span<const uint8_t>> Checked(MDB_dbi dbi, std::span<const uint8_t> key,
                                                   std::span<const uint8_t> stored) const;

  MDB_txn* txn_;
  const DbHandles* dbs_;
  const std::string* file_;
  const std::vector<std::string>* absent_;
  bool map_full_ = false;
};

class LmdbEnv {
 public:
  static absl::StatusOr<std::unique_ptr<LmdbEnv>> Open(const std::string& dir, const LmdbOptions& options);
  ~LmdbEnv();
  LmdbEnv(const LmdbEnv&) = delete;
  LmdbEnv& operator=(const LmdbEnv&) = delete;

  // Runs f in a write transaction and commits it. f may run more than once (after map growth) and
  // must not have effects outside the transaction until Write returns OK. A non-OK status from f
  // aborts the transaction and is returned.
  absl::Status Write(const std::function<absl::Status(LmdbTxn&)>& f) ABSL_LOCKS_EXCLUDED(writer_, resize_);
  // Runs f in a read-only snapshot, never older than one an earlier Read of this process saw.
  absl::Status Read(const std::function<absl::Status(LmdbTxn&)>& f) const;

  // Flushes to disk (for no_sync environments).
  absl::Status Sync();
  // Clears reader slots left by dead processes; returns how many.
  absl::StatusOr<int> ClearStaleReaders();
  // A consistent copy (compacted) into an existing empty directory, while writers go on.
  absl::Status CopyTo(const std::string& dir) const;

  size_t map_size() const ABSL_LOCKS_EXCLUDED(resize_) {
    absl::ReaderMutexLock lock(&resize_);
    return map_size_;
  }
  // Times Write grew the map since Open (for metrics).
  uint64_t growths() const { return growths_.load(std::memory_order_relaxed); }
  // Reader slots in use, by any process (mdb_env_info's me_numreaders: slots ever taken and not
  // yet cleared, so an upper bound of the readers active now).
  uint64_t readers() const;
  // Bytes of the data file in use (pages up to the last one written).
  absl::StatusOr<size_t> UsedBytes() const;
  const std::string& dir() const { return dir_; }
  // <dir>/data.mdb, as errors name it.
  const std::string& file() const { return file_; }
  // The latched error of a failed commit or sync, OK when healthy.
  absl::Status health() const ABSL_LOCKS_EXCLUDED(latch_mutex_);

 private:
  LmdbEnv(MDB_env* env, std::string dir, size_t map_size)
      : env_(env), dir_(std::move(dir)), file_(dir_ + "/data.mdb"), map_size_(map_size) {}
  absl::Status Grow() ABSL_LOCKS_EXCLUDED(resize_);
  absl::Status OpenDatabases(const std::vector<std::string>& names, bool read_only);
  // Writes the record format marker into a new environment (a writable one); refuses one of
  // another format.
  absl::Status CheckRecordFormat(LmdbTxn& txn, bool read_only);
  void Latch(const absl::Status& status) ABSL_LOCKS_EXCLUDED(latch_mutex_);
  // mdb_txn_commit, counted for BeginSnapshot.
  int Commit(MDB_txn* txn);
  // A read transaction whose snapshot is the one its txnid names (docs/storage.md, "Read
  // snapshots"): liblmdb copies the snapshot's roots from the meta page of its txnid after
  // choosing it, and a writer two commits further overwrites that page, so a reader preempted
  // in between could see a newer snapshot than the next reader, or a torn mix. A begin with two
  // commits started during it is retried.
  int BeginSnapshot(MDB_txn** txn) const;

  MDB_env* env_;
  std::string dir_;
  std::string file_;
  size_t map_size_ ABSL_GUARDED_BY(resize_);
  base::Mutex writer_;  // guards no member: one write transaction at a time
  std::atomic<uint64_t> commits_started_ = 0, commits_ended_ = 0;  // of Commit
  std::atomic<uint64_t> growths_ = 0;
  // Read transactions (and the write transaction) shared, map growth exclusive. absl::Mutex, not
  // std::shared_mutex (nor base::SharedMutex, which is one): glibc's rwlock prefers readers, so a
  // steady stream of reads starved Grow (and the writer behind it) indefinitely; absl::Mutex makes
  // new readers wait behind a waiting Grow. It is the one lock TSan cannot see (base/mutex.h says
  // why): what it orders is liblmdb's own state, which TSan does not see either, and map_size_,
  // which only Grow writes, with writer_ (a lock TSan sees) held as well.
  mutable absl::Mutex resize_;
  mutable base::Mutex latch_mutex_;
  absl::Status latched_ ABSL_GUARDED_BY(latch_mutex_);
  DbHandles dbs_;  // written once, at Open
  std::vector<std::string> absent_;  // declared databases a read-only file does not hold
  bool read_only_ = false;
};

}  // namespace fremen::storage
