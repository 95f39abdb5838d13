// One open map: its shards, its write-ahead log and the committer thread that turns submitted
// batches into durable, applied, acknowledged ones (storage/README.md, "Write path").
//
// Write path: Submit() validates a batch and queues it (ResourceExhausted marked IsQueueFull when
// the queue is full: the caller slows down — backpressure, not unbounded buffering). The committer
// takes every queued batch, appends the new ones to the log and syncs once (group commit), has each
// shard's thread fold its part in, and then calls each batch's callback with its acknowledgement.
// A retry of a batch already applied — the same (writer, sequence) and the same content — is
// acknowledged as a duplicate and not applied again; a (writer, sequence) used for other content is
// refused (BatchAck::error, storage/dedup_table.h). Checkpoints (by log size or on request) write
// the changed states of every shard to LMDB and drop the covered log segments. Open() recovers:
// every shard from its checkpoint, then the log after it.
//
// Storage errors (a failed log sync, commit or checkpoint: a full disk, an I/O error) latch: from
// then on every write is refused at once with that error (WriteError: ResourceExhausted for a full
// disk, Unavailable for any other cause, named in the message), and waiters of OnRoom are woken,
// so that no caller mistakes a failed map for a busy one.
//
// Reads run concurrently with writes and see every acknowledged batch.
// Thread-safety: every public method may be called from any thread.
#pragma once

#include <atomic>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "storage/batch.h"
#include "storage/cell_key.h"
#include "storage/dedup_table.h"
#include "storage/env/env.h"
#include "storage/map_info.h"
#include "storage/shard.h"
#include "storage/shard_workers.h"
#include "storage/update_record.h"
#include "storage/verify.h"
#include "storage/wal/wal.h"

namespace fremen::storage {

struct StoreOptions {
  // Shards of a new map when its info asks for 0. Default: one per core.
  uint32_t default_shards = 0;
  // Initial LMDB map size of each shard; grown on demand. Default: 64 MiB.
  size_t initial_map_size = 64ull << 20;
  // A checkpoint starts once the log holds this much; larger = fewer, longer checkpoints and a
  // longer recovery. Default: 256 MiB.
  uint64_t checkpoint_log_bytes = 256ull << 20;
  // Log segment size. Default: 64 MiB.
  uint64_t log_segment_bytes = 64ull << 20;
  // Observations queued but not yet applied beyond which Submit refuses (ResourceExhausted).
  // Default: 16M (about 100 MB of queued scans).
  uint64_t max_queued_observations = 16ull << 20;
  // The file system of the logs and of the small files a map keeps (env/env.h; LMDB does its own
  // I/O); tests inject faults through it. REQUIRES: outlives the stores. Default: Env::Default().
  Env* env = Env::Default();
  // Where a store reports what it repaired on its own (a torn log tail cut at recovery): one line
  // at a time, possibly from several threads at once. Default: none — the line goes to stderr.
  std::function<void(const std::string&)> log_warning;
  // Observations after which a state's float spectrum is folded in double (model/wide_bodies.h).
  // Default: model::kCompactRecordLimit; tests lower it.
  uint32_t widen_records_at = model::kCompactRecordLimit;
  // Before a map is opened, walk its shards' LMDB files in a child process (storage/lmdb/lmdb_probe.h):
  // LMDB aborts the process on some damaged pages, and a damaged map must fail alone, naming its
  // file, not take the daemon down. Costs one read of the files at open. Default: true.
  bool probe_before_open = true;
  // Test only: a publication waits before its first slice until a batch has been applied and
  // acknowledged, so that a test sees batches acknowledged while a publication runs however long
  // a slice takes against a log sync. Default: false.
  bool publication_waits_for_a_batch = false;
};

// Whether `status` is Submit's refusal for a full queue — backpressure: resubmit once OnRoom calls
// back — rather than a refusal that waiting does not cure (a latched storage error may be
// ResourceExhausted too: a full disk).
bool IsQueueFull(const absl::Status& status);

struct MapStats {
  ShardStats totals;  // summed over shards
  uint64_t log_bytes = 0;
  uint64_t last_lsn = 0;
  // Eq. 16: the raw observations (one bit each) over the bytes that hold the models.
  double compression_ratio = 0;
  // Mean ε_p (decayed prequential error at the selected order) over dynamic states with evidence.
  double mean_prediction_error = 0;
  // Lossless maps: ε_e and ε_p over all observed slots of all states (eq. 15).
  double estimation_error = 0;
  double lossless_prediction_error = 0;
  // What the last update job did, kept across restarts (RecordUpdate); nullopt before the first.
  std::optional<UpdateRecord> last_update;
};

class MapStore {
 public:
  using AckCallback = std::function<void(absl::StatusOr<BatchAck>)>;

  static absl::StatusOr<std::unique_ptr<MapStore>> Open(const MapInfo& info, const std::string& dir,
                                                        const StoreOptions& options)
      ABSL_NO_THREAD_SAFETY_ANALYSIS;  // see Recover
  ~MapStore();

  const MapInfo& info() const { return info_; }
  const model::ModelSettings& settings() const { return *settings_; }

  // --- writes ---
  // Validates and queues; `done` runs (on the committer thread) once the batch is durable and
  // applied, or refused as a whole (an ack whose `error` is set: nothing applied, the map goes on),
  // or failed (an error status: the map refuses writes from now on). An error returned here means
  // `done` will not run: the batch is unusable (InvalidArgument, OutOfRange), the queue is full
  // (IsQueueFull), the map is closing (Unavailable) or refuses writes (WriteError()).
  absl::Status Submit(ObservationBatch batch, AckCallback done) ABSL_LOCKS_EXCLUDED(queue_mutex_);
  // Submit and wait. A batch refused as a whole comes back as its ack's error.
  absl::StatusOr<BatchAck> Write(ObservationBatch batch);
  // Runs `f` once when the queue can take a batch of `observations` — by the same rule Submit
  // applies — or the map stops taking writes (closing, or a latched error: then Submit tells why),
  // on a store thread, or at once when either holds now. A streaming handler whose Submit was
  // refused stops reading and resumes from here, instead of polling.
  void OnRoom(uint64_t observations, std::function<void()> f) ABSL_LOCKS_EXCLUDED(queue_mutex_);
  // The highest sequence of `writer` logged in this map (so applied, or to be applied before any
  // later batch), 0 when none: where a writer that lost its count continues.
  uint64_t LastSequence(uint64_t writer) const ABSL_LOCKS_EXCLUDED(dedup_mutex_);
  // Checkpoints now and waits.
  absl::Status Checkpoint();
  // The update job's core (Shard::BeginPublication): republishes P, with its best order, of every
  // dynamic state observed since its last publication; logged so that recovery repeats it at the
  // same point among the batches. It is served a slice at a time between the batches that arrive
  // meanwhile, which are acknowledged as usual; checkpoints wait for it. Waits; returns the states
  // published. `progress(done, total)` is called from time to time while the shards publish.
  absl::StatusOr<uint64_t> PublishModels(std::function<void(uint64_t, uint64_t)> progress = nullptr);
  // Keeps what an update job did, for Stats(), in <dir>/last_update (replaced atomically).
  absl::Status RecordUpdate(const UpdateRecord& record) ABSL_LOCKS_EXCLUDED(last_update_mutex_);
  // Stops accepting writes, finishes the queued ones and checkpoints. Idempotent.
  absl::Status Close() ABSL_LOCKS_EXCLUDED(queue_mutex_);
  // OK, or the error that stopped all writes to the map (a failed log sync, commit or checkpoint:
  // latched, so that nothing is acknowledged that might not be durable; no checkpoint or backup
  // is written after it either — the log holds every applied batch). Reads still work.
  absl::Status WriteError() const ABSL_LOCKS_EXCLUDED(queue_mutex_);

  // --- reads ---
  // p at every (time, key): out[i·keys + j] for times[i], keys[j].
  std::vector<float> Predict(std::span<const uint64_t> keys, std::span<const double> times,
                             const PredictOptions& options) const;
  // p(t) of every cell of a box of a grid, x fastest; unobserved cells 0.5.
  absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options, std::vector<float>& out) const;
  std::optional<StateSnapshot> Snapshot(uint64_t key) const;
  // observed[i]: whether keys[i] was ever observed.
  std::vector<uint8_t> Observed(std::span<const uint64_t> keys) const;
  std::optional<std::pair<std::string, std::string>> Label(uint64_t key) const { return ShardFor(key).Label(key); }
  // The n states of `group` most likely to be 1 at t, most likely first.
  absl::StatusOr<std::vector<std::pair<uint64_t, float>>> TopN(const std::string& group, double t, size_t n,
                                                               const PredictOptions& options) const
      ABSL_LOCKS_EXCLUDED(groups_mutex_);
  MapStats Stats() const ABSL_LOCKS_EXCLUDED(last_update_mutex_);
  // A consistent copy of every shard and the map's info into `dir` (created, must be empty).
  // Returns the bytes written.
  absl::StatusOr<uint64_t> Backup(const std::string& dir) ABSL_LOCKS_EXCLUDED(backup_mutex_);
  // Verifies the map's files while it serves (storage/verify.h). Each shard is read in a forked
  // child process through LMDB's reader table: LMDB allows one environment per file per process,
  // and an abort on a damaged page ends the child, not the daemon. Checkpoints wait meanwhile (as
  // for a backup), so that the shards and the log are read at one position and no log segment is
  // dropped while it is read; batches go on being logged and acknowledged.
  // A shard not read by `deadline` is reported "not verified".
  VerifyReport Verify(absl::Time deadline = absl::InfiniteFuture()) ABSL_LOCKS_EXCLUDED(backup_mutex_);

 private:
  // A submitted batch. Everything that needs no shared state — classification, the log record,
  // the split by shard — is prepared by the submitting thread, off the committer's critical path.
  struct Pending {
    ObservationBatch batch;
    AckCallback done;
    BatchAck ack;
    std::vector<uint8_t> accept;
    std::string record;                        // the log record
    std::vector<std::vector<uint64_t>> keys;   // accepted observations by shard
    std::vector<std::vector<float>> values;
    std::vector<std::vector<StateLabel>> labels;  // the batch's labels by shard
    uint64_t fingerprint = 0;  // BatchFingerprint of the record's batch
  };
  // Requests the committer serves between groups, in order.
  struct Control {
    enum class Kind { kCheckpoint, kPublish } kind;
    std::function<void(absl::StatusOr<uint64_t>)> done;
    std::function<void(uint64_t, uint64_t)> progress;
    uint64_t lsn = 0;  // a publication's log record
  };
  // What the committer hands the applier: a logged group and the requests after it. The committer
  // logs and syncs the next group while the applier applies this one, so that the sync's wait
  // overlaps useful work.
  struct Stage {
    std::vector<Pending> group;     // logged; failed batches were answered already
    std::vector<Control> controls;  // served in order, after the group
    uint64_t group_lsn = 0;         // the log position once the group is applied
    bool final = false;             // the map is closing: checkpoint and stop
  };

  MapStore(MapInfo info, std::string dir, StoreOptions options, std::unique_ptr<model::ModelSettings> settings);
  // Not analysed: Open and Recover fill the guarded members before the store is shared (its
  // threads start last), when there is nothing to lock against.
  absl::Status Recover() ABSL_NO_THREAD_SAFETY_ANALYSIS;
  // Reports a repair through StoreOptions::log_warning.
  void Warn(const std::string& message) const;
  void CommitLoop();
  // Appends the group's new batches to the log (marking retries as duplicates, refusing reused
  // sequences).
  void LogGroup(std::vector<Pending>& group) ABSL_EXCLUSIVE_LOCKS_REQUIRED(wal_mutex_)
      ABSL_LOCKS_EXCLUDED(dedup_mutex_);
  void Latch(const absl::Status& status) ABSL_LOCKS_EXCLUDED(queue_mutex_);
  void ApplyLoop();
  void ApplyGroup(std::vector<Pending>& group);
  // Checkpoints at `lsn` in two steps (Shard::PrepareCheckpoint): the applier encodes every
  // shard's changed states — the only stall of ingest, a fraction of the write — and a background
  // thread writes them into LMDB, drops the covered log and then answers `waiting`. One image at a
  // time: a new checkpoint first waits for the previous write.
  void StartCheckpoint(uint64_t lsn, std::vector<Control> waiting);
  absl::Status WriteCheckpoint(uint64_t lsn, std::vector<Shard::CheckpointImage>& images)
      ABSL_LOCKS_EXCLUDED(backup_mutex_, wal_mutex_);
  bool CheckpointWriting() const;
  void WaitCheckpointWrite();
  // The applier's publication in progress (see PublishModels): Start marks the states (finishing
  // one still in progress first), Continue publishes a slice, Finish the rest.
  void StartPublication(Control control);
  void ContinuePublication();
  void FinishPublication();
  absl::StatusOr<uint64_t> RunControl(Control::Kind kind, std::function<void(uint64_t, uint64_t)> progress = nullptr);
  // Splits the accepted observations and the labels of a batch by shard.
  void SplitByShard(Pending& pending) const;
  // Classifies, encodes and splits a batch.
  Pending Prepare(ObservationBatch batch, AckCallback done) const;
  void IndexLabels(std::span<const StateLabel> labels) ABSL_LOCKS_EXCLUDED(groups_mutex_);
  // Whether the queue takes n more observations. One batch is always let in, however big, so that
  // a single huge scan is not refused forever.
  bool FitsLocked(uint64_t n) const ABSL_SHARED_LOCKS_REQUIRED(queue_mutex_) {
    return queued_observations_ == 0 || queued_observations_ + n <= options_.max_queued_observations;
  }
  const Shard& ShardFor(uint64_t key) const { return *shards_[ShardOf(key, info_.shards)]; }

  const MapInfo info_;
  const std::string dir_;
  const StoreOptions options_;
  std::unique_ptr<model::ModelSettings> settings_;
  std::vector<std::unique_ptr<Shard>> shards_;
  std::unique_ptr<ShardWorkers> workers_;
  // Not ABSL_PT_GUARDED_BY(wal_mutex_): its counters (bytes, durable_lsn) are atomics that the
  // applier and Stats read without it.
  std::unique_ptr<WalWriter> wal_;
  base::Mutex wal_mutex_;      // the committer's appends and syncs, the applier's drops
  mutable base::Mutex dedup_mutex_;  // held by the committer to change dedup_, by LastSequence to read it
  DedupTable dedup_ ABSL_GUARDED_BY(dedup_mutex_);  // the committer's: what was logged
  DedupTable applied_dedup_;  // applier only: what was applied, recorded by checkpoints
  uint64_t applied_lsn_ = 0;  // applier only
  std::optional<Control> publication_;     // applier only: the publication in progress
  uint64_t publication_total_ = 0;         // applier only: its states
  bool publication_held_ = false;          // applier only: see StoreOptions::publication_waits_for_a_batch
  std::vector<Control> waiting_checkpoints_;  // applier only: checkpoints asked during a publication
  std::future<void> checkpoint_write_;        // applier only: the image being written, if any

  mutable base::Mutex queue_mutex_;
  base::CondVar queue_ready_;
  std::deque<Pending> queue_ ABSL_GUARDED_BY(queue_mutex_);
  uint64_t queued_observations_ ABSL_GUARDED_BY(queue_mutex_) = 0;
  bool closing_ ABSL_GUARDED_BY(queue_mutex_) = false;
  std::vector<Control> controls_ ABSL_GUARDED_BY(queue_mutex_);
  std::vector<std::function<void()>> room_waiters_ ABSL_GUARDED_BY(queue_mutex_);
  // Latched: a failed log sync or checkpoint stops all writes.
  absl::Status write_error_ ABSL_GUARDED_BY(queue_mutex_);

  // Guards no member: held by checkpoints and backups, so that a backup sees one checkpoint.
  base::Mutex backup_mutex_;

  mutable base::Mutex last_update_mutex_;
  std::optional<UpdateRecord> last_update_ ABSL_GUARDED_BY(last_update_mutex_);

  mutable base::Mutex groups_mutex_;
  absl::flat_hash_map<std::string, std::vector<uint64_t>> groups_ ABSL_GUARDED_BY(groups_mutex_);

  base::Mutex stage_mutex_;
  base::CondVar stage_changed_;
  std::deque<Stage> stages_ ABSL_GUARDED_BY(stage_mutex_);

  std::thread committer_;
  std::thread applier_;
};

}  // namespace fremen::storage
