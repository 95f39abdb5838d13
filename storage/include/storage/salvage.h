// The salvage of a damaged map: a new map holding every record of the damaged one that verifies,
// and a report of what was lost ("keep what verifies, report what was lost"). An operator's explicit
// action (Store::SalvageMap, AdminService.SalvageMap, `fremenctl salvage`) on a map that failed to
// open; the damaged map and its files are left exactly as they are.
//
// Shards: each database of each shard is read in a forked child (storage/isolated_child.h), which
// scans it with the checked scan and streams every record over a pipe; the parent checks each
// (storage/shard_record_checks.h) and writes those that pass into the new shard's fresh LMDB file.
// A child that LMDB aborts keeps what it sent; the rest of that database is lost. Then the shard
// invariants the loader relies on are restored: a lossless history or wide body whose state was
// lost is dropped, a state stored both as never changed and as changed keeps its changed model,
// the touched list names only surviving states (none survives its own loss: then every state counts
// as touched, as in a shard that never had the list). A label that verifies is kept even when its
// state's model was lost: the loader needs no state for it, and its name still names that state
// (which then answers as unobserved).
//
// Log: the records up to the first damaged one (or the first that does not decode) are written to
// the new map's wal/ under their own LSNs, so that the normal recovery replays them on top of the
// shards' checkpoints; the bytes and records after it are lost. A torn tail is not a loss. A shard
// whose checkpoint LSN was lost gets the newest LSN the salvage knows (no log record is applied to
// it twice); a shard behind the newest checkpoint while the kept log ends short of it is raised to
// that checkpoint (the records it lacks are gone), so that the new map opens.
//
// Thread-safety: SalvageFiles reads files no process writes (a failed map is not open) and writes
// a directory only it uses.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/map_info.h"
#include "storage/map_store.h"
#include "storage/verify.h"

namespace fremen::storage {

// Losses listed one by one in a report; the others are only counted.
inline constexpr size_t kMaxListedLosses = 100;

struct SalvageDatabase {
  std::string name;  // storage/shard_records.h: "static", "dynamic", ...
  uint64_t kept = 0;
  uint64_t lost = 0;  // records that failed a check, were dropped for a lost state, or were not read
};

struct SalvageShard {
  uint32_t shard = 0;
  std::vector<SalvageDatabase> databases;  // in shard_records::AllDatabases() order
  uint64_t kept() const;
  uint64_t lost() const;
};

struct SalvageLog {
  uint64_t records_kept = 0;     // records copied into the new map's log
  uint64_t bytes_kept = 0;       // their bytes, headers included
  uint64_t last_lsn = 0;         // the last record kept; 0 when none
  uint64_t records_lost = 0;     // after the first damaged record: it and every later intact one found
  uint64_t bytes_lost = 0;       // from the first damaged record to the end of the log
  uint64_t torn_tail_bytes = 0;  // an incomplete last record (never acknowledged): not a loss
};

struct SalvageReport {
  MapInfo map;       // the new map
  std::string from;  // the damaged map's name
  std::vector<SalvageShard> shards;
  SalvageLog log;
  // What was lost and why, file/where/what as the verifier says it; the first kMaxListedLosses.
  std::vector<VerifyProblem> lost;
  uint64_t losses = 0;            // all of them, listed or not
  uint64_t records_kept() const;  // of every shard
  uint64_t records_lost() const;
};

// Writes into `to_dir` (shard-N/, wal/; created) everything of the map in `from_dir` that verifies,
// as `info` describes the map. Errors only for what prevents the salvage itself (the new files
// cannot be written, the map's settings are invalid) or end it (DeadlineExceeded: `deadline` came
// before every record was read); damage is the report's.
absl::StatusOr<SalvageReport> SalvageFiles(const std::string& from_dir, const std::string& to_dir, const MapInfo& info,
                                           const StoreOptions& options, absl::Time deadline = absl::InfiniteFuture());

}  // namespace fremen::storage
