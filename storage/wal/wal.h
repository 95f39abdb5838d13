// The write-ahead log of one map: an append-only sequence of records, each acknowledged batch of
// observations, made durable by group commit (many records, one fdatasync) and replayed after a
// crash on top of the last checkpoint (PERF-NOTES: LMDB cannot sit on the per-observation path).
//
// Files: <dir>/wal-<first LSN, 20 digits>.log, rolled over at Options::segment_bytes. A record is
//   u32 payload length | u32 CRC-32 of (LSN, payload) | u64 LSN | payload        (little-endian)
// LSNs are consecutive from 1. A torn or corrupt tail (a crash mid-write: never acknowledged, as
// acknowledgements wait for Sync) ends the log: replay stops there and the writer truncates it.
// Corruption before the tail — a bad record followed by good ones — is reported as DataLoss.
//
// Thread-safety: WalWriter is used by one thread (the map's committer); Replay by one thread
// before the writer opens.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fremen::storage {

struct WalOptions {
  // A new segment starts once the current one passes this size; checkpoints delete whole
  // segments, so smaller segments free space sooner at the cost of more files. Default: 64 MiB.
  uint64_t segment_bytes = 64ull << 20;
  // Fault injection for tests: called before each write+sync; an error is treated exactly like a
  // failed write (it latches). Default: none.
  std::function<absl::Status()> inject_fault;
};

struct WalReplayResult {
  uint64_t last_lsn = 0;       // the last intact record (0: none)
  uint64_t records = 0;        // records passed to the callback
  bool truncated_tail = false; // a torn/corrupt tail was found (and will be cut by the writer)
};

// Calls f(lsn, payload) for every intact record with LSN > after_lsn, in order. f's error stops the
// replay and is returned.
absl::StatusOr<WalReplayResult> ReplayWal(const std::string& dir, uint64_t after_lsn,
                                          const std::function<absl::Status(uint64_t, std::span<const uint8_t>)>& f);

class WalWriter {
 public:
  // Opens the log for appending after its last intact record, cutting a torn tail.
  static absl::StatusOr<std::unique_ptr<WalWriter>> Open(const std::string& dir, const WalOptions& options);
  ~WalWriter();

  // Buffers one record; returns its LSN. Nothing is durable until Sync() returns OK.
  uint64_t Append(std::span<const uint8_t> payload);
  // Writes the buffered records and fdatasyncs. A failure latches: every later Sync fails too, so
  // that nothing is acknowledged after an I/O error (the bytes on disk are unknown).
  absl::Status Sync();
  // Deletes segments whose records all have LSN ≤ lsn (the checkpoint covers them).
  absl::Status DropThrough(uint64_t lsn);

  uint64_t last_lsn() const { return next_lsn_ - 1; }
  // These two may be read from any thread (for statistics).
  uint64_t durable_lsn() const { return durable_lsn_.load(std::memory_order_relaxed); }
  // Bytes in all live segments.
  uint64_t bytes() const { return bytes_.load(std::memory_order_relaxed); }

 private:
  WalWriter(std::string dir, WalOptions options) : dir_(std::move(dir)), options_(options) {}
  absl::Status OpenSegment(uint64_t first_lsn);

  std::string dir_;
  WalOptions options_;
  int fd_ = -1;
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
