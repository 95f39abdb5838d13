// What a map remembers of each writer's recent batches, to tell a retry from new data: per writer,
// the fingerprints (storage/batch.h: BatchFingerprint) of the kWindow highest sequences applied.
//
// The contract (proto/fremen/v1/ingest.proto): a batch is a duplicate only if it is the same batch.
// - (writer, sequence) recorded with the same fingerprint: a retry — acknowledged, not applied again.
// - recorded with another fingerprint: the sequence was used for a different batch (a writer that
//   restarted its count) — AlreadyExists naming writer and sequence, never a silent drop.
// - below the writer's floor (sequences that fell out of the window): its content is not
//   known any more, so a retry cannot be told from new data — AlreadyExists too.
// - anything else (above the floor and not recorded, e.g. a gap of the writer's count): new.
// Every error says where the writer may continue: after its last (highest) sequence.
//
// Persisted with every checkpoint (in each shard's meta) and rebuilt from the write-ahead log
// after it; Decode is strict (DataLoss on any malformed byte). Thread-safety: none (the map's
// committer and applier each own one).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "absl/container/btree_map.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fremen::storage {

class DedupTable {
 public:
  // Sequences remembered per writer. A retry is recognised when it is among the writer's kWindow
  // highest sequences: the client libraries resend at most their unacknowledged batches (64 by
  // default), far fewer. Bounds the table: about 16 bytes a sequence in memory, 9 in a checkpoint.
  static constexpr size_t kWindow = 256;

  // true: this very batch was recorded (a retry); false: new; AlreadyExists otherwise (see above).
  absl::StatusOr<bool> Seen(uint64_t writer, uint64_t sequence, uint64_t fingerprint) const;
  // Remembers an applied batch; the writer's lowest sequence leaves the window beyond kWindow.
  // A sequence below the floor is ignored (replay may record again what a checkpoint has).
  void Record(uint64_t writer, uint64_t sequence, uint64_t fingerprint);
  // The writer's highest recorded sequence; 0 when none.
  uint64_t LastSequence(uint64_t writer) const;
  // Both tables' sequences per writer (the higher floor, the kWindow highest sequences). Merging the
  // tables of two checkpoints of one map gives the later one's.
  void MergeFrom(const DedupTable& other);
  size_t writers() const { return writers_.size(); }

  std::string Encode() const;
  static absl::StatusOr<DedupTable> Decode(std::string_view bytes);
  bool operator==(const DedupTable&) const = default;

 private:
  struct Writer {
    uint64_t floor = 0;                          // every sequence < floor has left the window
    absl::btree_map<uint64_t, uint64_t> recent;  // sequence → fingerprint; never empty
    bool operator==(const Writer&) const = default;
  };

  absl::flat_hash_map<uint64_t, Writer> writers_;
};

}  // namespace fremen::storage
