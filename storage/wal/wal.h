// The write-ahead log of one map: an append-only sequence of records, each acknowledged batch of
// observations, made durable by group commit (many records, one fdatasync) and replayed after a
// crash on top of the last checkpoint (docs/performance.md, "LMDB cannot sit on the
// per-observation path").
//
// Files: <dir>/wal-<first LSN, 20 digits>.log, rolled over at Options::segment_bytes. A record is
//   u32 payload length | u32 CRC-32 of (LSN, payload) | u64 LSN | payload        (little-endian)
// LSNs are consecutive within the log, from 1 or from the segment a recovery opened at its LSN
// floor (WalOptions::min_next_lsn); a gap between segments is legitimate only where a checkpoint
// covers every missing LSN.
//
// Torn tail or corruption (storage/README.md, "Torn tail and corruption"): only an incomplete
// record at the very end of the newest segment — header or payload running past the end of the
// file, or a last record whose CRC fails with no intact record after it — is a torn tail: a
// crash mid-write, never acknowledged (acknowledgements wait for Sync). Replay stops before it and
// reports its size; the writer cuts it. Anything else — a damaged record followed by bytes that
// parse as an intact record with a plausible LSN, a damaged older segment, an intact record out of
// sequence — is corruption: DataLoss naming the file, byte offset and LSN, and nothing is cut.
//
// Thread-safety: WalWriter is used by one thread (the map's committer); Replay by one thread
// before the writer opens.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "storage/env/env.h"

namespace fremen::storage {

struct WalReplayResult;

struct WalOptions {
  // A new segment starts once the current one passes this size; checkpoints delete whole
  // segments, so smaller segments free space sooner at the cost of more files. Default: 64 MiB.
  uint64_t segment_bytes = 64ull << 20;
  // Where the segments are read and written; tests inject faults through it.
  // REQUIRES: outlives the writer. Default: Env::Default().
  Env* env = Env::Default();
  // The LSN floor: the next record gets at least this LSN. A recovery passes its highest checkpoint
  // LSN + 1, so that no new record can fall at or below a checkpoint (a later recovery would skip
  // it as checkpointed). When the log ends below it, a new segment starts at the floor.
  // Default: 1.
  uint64_t min_next_lsn = 1;
  // The replay of this log that came just before (a recovery's), or null. Its scan of the newest
  // segment stands in for the writer's own when it names the same segment: the writer then cuts
  // the torn tail the replay found instead of reading and checking the segment a second time (up
  // to a segment's size, tens of MB, of a recovery's reading). Nothing may write the log between
  // the replay and the writer's Open.
  const WalReplayResult* replayed = nullptr;
};

struct WalReplayResult {
  uint64_t last_lsn = 0;        // the last intact record (0: none)
  uint64_t records = 0;         // records passed to the callback
  bool truncated_tail = false;  // a torn tail was found (the writer cuts it when it opens)
  // Where the torn tail starts and how long it is, for the warning the caller logs.
  std::string torn_tail_file;
  uint64_t torn_tail_offset = 0;
  uint64_t torn_tail_bytes = 0;
  // The newest segment, as the replay found it (always read, even when a checkpoint covers it):
  // its first LSN and the length of its prefix of intact records in sequence. For WalWriter::Open
  // (WalOptions::replayed). newest_segment_scanned is false when the log had no segment.
  bool newest_segment_scanned = false;
  uint64_t newest_segment_first = 0;
  uint64_t newest_segment_intact_bytes = 0;
};

// Where a replay that failed stopped: the first record it did not replay (damaged, out of sequence,
// refused by the callback, or the start of a segment after a gap), for a salvage that keeps the log
// before it (storage/salvage.h).
struct WalStop {
  std::string file;                // the segment's path
  uint64_t offset = 0;             // the record's byte offset in it
  uint64_t lsn = 0;                // the LSN expected there
  uint64_t bytes_after = 0;        // from there to the end of the log, later segments included
  uint64_t highest_lsn_after = 0;  // the highest LSN of an intact record found after it; 0: none
};

// Calls f(lsn, payload) for every intact record with LSN > after_lsn, in order. f's error stops the
// replay and is returned. Corruption (see above) is DataLoss; a gap between segments is DataLoss
// unless after_lsn covers it. When it fails, `stop` (if given) says where.
absl::StatusOr<WalReplayResult> ReplayWal(const std::string& dir, uint64_t after_lsn,
                                          const std::function<absl::Status(uint64_t, std::span<const uint8_t>)>& f,
                                          Env* env = Env::Default(), WalStop* stop = nullptr);

class WalWriter {
 public:
  // Opens the log for appending after its last intact record (or at options.min_next_lsn, if
  // higher), cutting a torn tail of the newest segment. Only the newest segment is read: corruption
  // there is DataLoss and nothing is cut; older segments are ReplayWal's business.
  static absl::StatusOr<std::unique_ptr<WalWriter>> Open(const std::string& dir, const WalOptions& options);
  ~WalWriter();

  // Buffers one record; returns its LSN. Nothing is durable until Sync() returns OK.
  uint64_t Append(std::span<const uint8_t> payload);
  // Writes the buffered records and fdatasyncs. A failure latches: every later Sync fails too, so
  // that nothing is acknowledged after an I/O error (the bytes on disk are unknown). ENOSPC is
  // ResourceExhausted (see env.h).
  absl::Status Sync();
  // Deletes segments whose records all have LSN ≤ lsn (the checkpoint covers them).
  absl::Status DropThrough(uint64_t lsn);

  uint64_t last_lsn() const { return next_lsn_ - 1; }
  // These two may be read from any thread (for statistics).
  uint64_t durable_lsn() const { return durable_lsn_.load(std::memory_order_relaxed); }
  // Bytes in all live segments.
  uint64_t bytes() const { return bytes_.load(std::memory_order_relaxed); }

 private:
  WalWriter(std::string dir, WalOptions options) : dir_(std::move(dir)), options_(options), env_(options.env) {}
  absl::Status OpenSegment(uint64_t first_lsn);

  std::string dir_;
  WalOptions options_;
  Env* const env_;
  std::unique_ptr<WritableFile> file_;  // the newest segment
  uint64_t segment_size_ = 0;
  uint64_t next_lsn_ = 1;
  std::atomic<uint64_t> durable_lsn_ = 0;
  std::atomic<uint64_t> bytes_ = 0;
  std::vector<uint8_t> buffer_;
  uint64_t first_buffered_lsn_ = 0;
  struct Segment {
    uint64_t first_lsn;
    uint64_t bytes;
  };
  std::vector<Segment> segments_;  // oldest first; the last is open for appending
  absl::Status latched_;
};

}  // namespace fremen::storage
