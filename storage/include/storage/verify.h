// The verifier of a map's files, for operators (`fremend --verify`, `fremenctl check`, restore of a
// backup), in the spirit of fsck / mdb_stat / `etcdctl check`: it reads every record of every shard
// and every record of the write-ahead log, decodes each with the codec that wrote it, checks the
// invariants that tie them together, and reports what it found. It never writes: LMDB files are
// opened read-only (MDB_RDONLY) and the log is only read (ReplayWal; nothing is truncated).
//
// What is checked:
// - every shard's data.mdb: each record of each database decodes (storage/shard_records.h names
//   them: never-changed bricks, state models, lossless histories, wide bodies, labels, meta), its
//   key is 8 bytes, belongs to this shard and (grids) to a cell of the grid; lossless histories and
//   wide bodies have their state; no state is both never-changed and changed; the touched list
//   names changed states; the dedup table and the checkpoint LSN decode. A read error of LMDB
//   (DataLoss from a checksum, MDB_CORRUPTED) is a problem, and verification goes on with the next
//   database and shard.
// - the log (<dir>/wal): every record replays, is a publication mark or decodes as a batch; a bad
//   record is named by segment, byte offset and the LSN before it. An incomplete record at the very
//   end of the newest segment is a torn tail (never acknowledged): a note, not a problem.
// - checkpoints against the log: no gap between the oldest shard checkpoint and the log's first
//   record, and no checkpoint past the log's last record (new records would reuse its LSNs).
//
// LMDB aborts the process on some damaged pages (mdb_assert). With VerifyOptions::isolate each
// shard is read in a forked child process; a child that dies becomes a problem "shard-N/data.mdb:
// LMDB aborted reading it (signal 6)" and the caller carries on.
//
// Thread-safety: VerifyMap may run concurrently with anything that does not write the files; for
// a map open for writing in this process see MapStore::Verify (LMDB allows one environment per
// file per process, and the log must not lose segments while it is read).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/time/time.h"
#include "storage/map_info.h"

namespace fremen::storage {

struct VerifyOptions {
  // Read each shard's LMDB file in a forked child process, so that an LMDB abort on a damaged page
  // is reported instead of ending the caller. Default: false.
  bool isolate = false;
  // The map is open for writing (by this process or another): LMDB files are read through the lock
  // file's reader table, so that the writer keeps the pages being read, and the end of the newest
  // log segment may be a record being written. Otherwise the files must be at rest and no lock
  // file is used or created (a backup directory is left exactly as it is). Default: false.
  bool live = false;
  // With isolate: a shard whose child has not finished by then is reported "not verified" (the
  // child is killed), so that a call's deadline bounds the check. Default: none.
  absl::Time deadline = absl::InfiniteFuture();
};

// One thing found wrong.
struct VerifyProblem {
  // The file, relative to the map's directory: "shard-2/data.mdb", "wal/wal-…-.log", "wal".
  std::string file;
  // Where in it: "dynamic record of state 1234", "byte 4096 (after LSN 17)"; may be empty.
  std::string where;
  std::string what;
};

struct ShardVerifyReport {
  uint32_t shard = 0;
  uint64_t records = 0;                    // records read, of every database
  uint64_t record_bytes = 0;               // their keys and values
  uint64_t file_bytes = 0;                 // size of data.mdb
  std::optional<uint64_t> checkpoint_lsn;  // none: the shard was never checkpointed
  bool read = false;                       // the file could be read to its end (problems may still have been found)
};

struct LogVerifyReport {
  uint64_t segments = 0;
  uint64_t records = 0;
  uint64_t bytes = 0;            // of every segment
  uint64_t first_lsn = 0;        // of the oldest segment; 0 when there is none
  uint64_t last_lsn = 0;         // the last intact record; 0 when there is none
  uint64_t torn_tail_bytes = 0;  // after the last intact record of the newest segment
};

struct VerifyReport {
  std::string map;
  std::string dir;
  std::vector<ShardVerifyReport> shards;
  LogVerifyReport log;
  std::vector<VerifyProblem> problems;
  // Worth knowing, not wrong (a torn tail, an unknown meta record).
  std::vector<std::string> notes;
  // VerifyOptions::deadline came first: the shards after the one it stopped are not in `shards`,
  // the log was not read, and `problems` says which shard was not verified.
  bool deadline_exceeded = false;

  bool clean() const { return problems.empty(); }
};

// Verifies the map whose files are in `dir` (shard-N/, wal/) as `info` describes it.
VerifyReport VerifyMap(const std::string& dir, const MapInfo& info, const VerifyOptions& options);

// Shards only (a backup holds no log): the same checks as VerifyMap without the log's.
VerifyReport VerifyShards(const std::string& dir, const MapInfo& info, const VerifyOptions& options);

// What a whole data directory holds (storage/store.h: catalog/, maps/<id>/).
struct DataDirVerifyReport {
  // Of the catalog and the maps directory; files relative to the data directory: a catalog record
  // that does not decode, a map whose directory is missing, a directory no catalog record names.
  std::vector<VerifyProblem> problems;
  // Every map the catalog lists, in name order.
  std::vector<VerifyReport> maps;

  bool clean() const;
};

// Verifies the catalog and every map of a data directory at rest (no daemon running on it: the
// caller holds its lock, server/daemon/data_dir_lock.h). The catalog is opened read-only.
DataDirVerifyReport VerifyDataDir(const std::string& data_dir, const VerifyOptions& options);

// "shard-2/data.mdb: dynamic record of state 1234: <what>" — one line, no map name.
std::string FormatProblem(const VerifyProblem& problem);

}  // namespace fremen::storage
