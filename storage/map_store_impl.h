// MapStoreImpl: the map store (storage/map_store.h) over its shards, write-ahead log and the
// committer and applier threads. Private to storage: the rest of the daemon sees MapStore.
// Thread-safety: as MapStore's.
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
#include "storage/dedup_table.h"
#include "storage/map_store.h"
#include "storage/shard.h"
#include "storage/shard_workers.h"
#include "storage/wal/wal.h"

namespace fremen::storage {

class MapStoreImpl final : public MapStore {
 public:
  static absl::StatusOr<std::unique_ptr<MapStoreImpl>> Open(const MapInfo& info, const std::string& dir,
                                                            const StoreOptions& options)
      ABSL_NO_THREAD_SAFETY_ANALYSIS;  // see Recover
  ~MapStoreImpl() override;

  const MapInfo& info() const override { return info_; }
  const model::ModelSettings& settings() const override { return *settings_; }

  absl::Status Submit(ObservationBatch batch, AckCallback done) override ABSL_LOCKS_EXCLUDED(queue_mutex_) {
    return Enqueue(std::move(batch), std::move(done), /*tail=*/false);
  }
  absl::StatusOr<BatchAck> Write(ObservationBatch batch) override;
  void OnRoom(uint64_t observations, std::function<void()> f) override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  uint64_t LastSequence(uint64_t writer) const override ABSL_LOCKS_EXCLUDED(dedup_mutex_);
  absl::Status Checkpoint() override;
  absl::StatusOr<uint64_t> PublishModels(std::function<void(uint64_t, uint64_t)> progress = nullptr) override;
  absl::Status RecordUpdate(const UpdateRecord& record) override ABSL_LOCKS_EXCLUDED(last_update_mutex_);
  absl::Status Close() override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  absl::Status WriteError() const override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  absl::Status StopWrites() override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  absl::Status ResumeWrites() override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  absl::Status MarkMoved(const std::string& to) override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  MoveStatus Move() const override ABSL_LOCKS_EXCLUDED(queue_mutex_);
  absl::Status StartTail() override ABSL_LOCKS_EXCLUDED(queue_mutex_, tail_mutex_);
  absl::StatusOr<std::vector<TailRecord>> Tail(uint64_t after) const override
      ABSL_LOCKS_EXCLUDED(queue_mutex_, tail_mutex_);
  absl::Status ApplyTail(uint64_t after, std::span<const TailRecord> tail) override ABSL_LOCKS_EXCLUDED(queue_mutex_);

  std::vector<float> Predict(std::span<const uint64_t> keys, std::span<const double> times,
                             const PredictOptions& options) const override;
  absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options,
                          std::vector<float>& out) const override;
  absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options,
                          std::span<float> out) const override;
  absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options,
                          std::span<uint8_t> out) const override;
  absl::StatusOr<BoxSeries> PlanBoxSeries(const CellBox& box, double t, const PredictOptions& options) const override;
  void PredictBoxSeries(const BoxSeries& plan, std::span<const double> times, std::vector<float>& out) const override;
  std::optional<StateSnapshot> Snapshot(uint64_t key) const override;
  std::vector<uint8_t> Observed(std::span<const uint64_t> keys) const override;
  std::vector<float> PredictWithObserved(std::span<const uint64_t> keys, std::span<const double> times,
                                         const PredictOptions& options, std::vector<uint8_t>& observed) const override;
  std::optional<std::pair<std::string, std::string>> Label(uint64_t key) const override {
    return ShardFor(key).Label(key);
  }
  absl::StatusOr<std::vector<StateLabel>> Labels(const std::string& group) const override
      ABSL_LOCKS_EXCLUDED(groups_mutex_);
  absl::StatusOr<std::vector<std::pair<uint64_t, float>>> TopN(const std::string& group, double t, size_t n,
                                                               const PredictOptions& options) const override
      ABSL_LOCKS_EXCLUDED(groups_mutex_);
  MapStats Stats() const override ABSL_LOCKS_EXCLUDED(last_update_mutex_);
  absl::StatusOr<uint64_t> Backup(const std::string& dir, uint64_t* lsn = nullptr) override
      ABSL_LOCKS_EXCLUDED(backup_mutex_);
  VerifyReport Verify(absl::Time deadline = absl::InfiniteFuture()) override ABSL_LOCKS_EXCLUDED(backup_mutex_);

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
    // A history's runs by shard: keys[s][previous run's end, end) were observed at `time`. Empty
    // for a scan, whose keys were all observed at batch.time.
    using Run = ObservationRun;
    std::vector<std::vector<Run>> runs;
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

  // A move's tail recorded while its snapshot is copied (StartTail).
  struct TailCapture {
    std::vector<TailRecord> records;
    uint64_t bytes = 0;
    std::string given_up;  // why the tail cannot be used, when not empty
  };

  // Submit; a move's tail (ApplyTail) is let into an incoming copy, past the queue's bound.
  absl::Status Enqueue(ObservationBatch batch, AckCallback done, bool tail) ABSL_LOCKS_EXCLUDED(queue_mutex_);
  // Records a logged batch (or gives the tail up for a publication) while a tail is captured.
  void CaptureTail(uint64_t lsn, const std::string& record) ABSL_LOCKS_EXCLUDED(tail_mutex_);
  void GiveUpTail(const std::string& why) ABSL_LOCKS_EXCLUDED(tail_mutex_);
  MapStoreImpl(MapInfo info, std::string dir, StoreOptions options, std::unique_ptr<model::ModelSettings> settings);
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
  // Splits the accepted observations and the labels of a batch by shard (a history's runs too).
  void SplitByShard(Pending& pending) const;
  // Folds shard s's part of a batch into it: a scan at `scan`'s time, a history run by run, each
  // run as the scan it stands for (so that a history and its scans give bit-identical models).
  void ApplyToShard(uint32_t s, const Pending& pending, const ScanContext& scan) const;
  // Classifies, encodes and splits a batch.
  Pending Prepare(ObservationBatch batch, AckCallback done) const;
  void IndexLabels(std::span<const StateLabel> labels) ABSL_LOCKS_EXCLUDED(groups_mutex_);
  // A copy of `group`'s keys (Labels, TopN); NOT_FOUND naming the group when no state has it.
  absl::StatusOr<std::vector<uint64_t>> GroupMembers(const std::string& group) const ABSL_LOCKS_EXCLUDED(groups_mutex_);
  // Whether the queue takes n more observations. One batch is always let in, however big, so that
  // a single huge scan is not refused forever.
  bool FitsLocked(uint64_t n) const ABSL_SHARED_LOCKS_REQUIRED(queue_mutex_) {
    return queued_observations_ == 0 || queued_observations_ + n <= options_.max_queued_observations;
  }
  const Shard& ShardFor(uint64_t key) const { return *shards_[ShardOf(key, info_.shards)]; }
  // OK when `box` is a non-empty box of this grid (FailedPrecondition on a generic map, OutOfRange).
  absl::Status CheckBox(const CellBox& box) const;
  // at[s]: the positions in `keys` of shard s's keys, in order.
  std::vector<std::vector<uint32_t>> PositionsByShard(std::span<const uint64_t> keys) const;
  // Predict's work; fills observed (keys.size() bytes) at the first time when it is not null.
  std::vector<float> PredictKeys(std::span<const uint64_t> keys, std::span<const double> times,
                                 const PredictOptions& options, uint8_t* observed) const;
  // From this many keys a time, Predict asks the shards at once, each on its own thread (as
  // PredictBox does from 2^16 cells): below it a thread's start costs more than it saves.
  static constexpr size_t kParallelPredictions = size_t{1} << 16;
  // PredictBox into the caller's floats or bytes.
  template <typename T>
  absl::Status PredictBoxInto(const CellBox& box, double t, const PredictOptions& options, std::span<T> out) const;

  const MapInfo info_;
  const std::string dir_;
  const StoreOptions options_;
  // options_.observer's for this map, or one that ignores everything: never null.
  const std::shared_ptr<MapObserver> observer_;
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
  // A move (StopWrites, MarkMoved): writes refused while not kServing.
  MoveStatus move_ ABSL_GUARDED_BY(queue_mutex_);

  // Held by checkpoints and backups, so that a backup sees one checkpoint.
  base::Mutex backup_mutex_;
  // The log position of the checkpoint on disk (every shard's), which a backup copies.
  uint64_t written_lsn_ ABSL_GUARDED_BY(backup_mutex_) = 0;

  mutable base::Mutex tail_mutex_;
  std::optional<TailCapture> tail_ ABSL_GUARDED_BY(tail_mutex_);

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
