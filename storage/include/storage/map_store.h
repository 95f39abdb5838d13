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
// Thread-safety: every method may be called from any thread.
//
// An interface, as leveldb's DB is: the implementation (MapStoreImpl, storage/map_store_impl.h)
// and its shards, log and threads are private to storage, so that what includes this header sees
// only the map's operations and their types.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "storage/batch.h"
#include "storage/cell_key.h"
#include "storage/env/env.h"
#include "storage/map_info.h"
#include "storage/model/kernels/wide_bodies.h"
#include "storage/model/model_settings.h"
#include "storage/queries.h"
#include "storage/shard_stats.h"
#include "storage/store_observer.h"
#include "storage/update_record.h"
#include "storage/verify.h"

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
  // An online move's tail (StartTail): the bytes of batches a map records while its snapshot is
  // copied, at most. Past it the tail is given up (Tail answers FailedPrecondition) and the move is
  // made again. Default: 256 MiB.
  uint64_t max_tail_bytes = 256ull << 20;
  // Test only: a publication waits before its first slice until a batch has been applied and
  // acknowledged, so that a test sees batches acknowledged while a publication runs however long
  // a slice takes against a log sync. Default: false.
  bool publication_waits_for_a_batch = false;
  // Told of every map's batches, log syncs, checkpoints and recovery (storage/store_observer.h),
  // for metrics. REQUIRES: outlives the stores. Default: none.
  StoreObserver* observer = nullptr;
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
  // Observations submitted but not yet taken by the committer (the queue Submit bounds).
  uint64_t queued_observations = 0;
  // The shards' LMDB environments: their map sizes summed, the times a write grew one (since the
  // map opened), and the reader slots in use (this process and others, such as a verifier).
  uint64_t lmdb_map_size_bytes = 0;
  uint64_t lmdb_growths = 0;
  uint64_t lmdb_readers = 0;
  // What the last update job did, kept across restarts (RecordUpdate); nullopt before the first.
  std::optional<UpdateRecord> last_update;
};

// Where a map is in a move to another daemon (docs/fleet.md, "Moving a map").
enum class MoveState {
  kServing,        // takes writes
  kWritesStopped,  // a move copies its tail (or, offline, the map): writes refused, until ResumeWrites or MarkMoved
  kMoved,          // the move is committed: writes refused for good (kept across a reopen)
  kCopying,        // an online move copies its snapshot: takes writes, recording them (StartTail)
  kIncoming,       // a move's copy waiting for its tail (ApplyTail): refuses writes (kept across a reopen)
};
struct MoveStatus {
  MoveState state = MoveState::kServing;
  std::string moved_to;   // kMoved: where it went
  uint64_t snapshot_lsn = 0;  // kIncoming: the snapshot's log position, which its tail continues
};

// The file in a map's directory (and in a backup's: RestoreMap copies it) that marks a move's copy
// waiting for its tail (kIncoming), holding the snapshot's LSN in decimal.
inline constexpr char kIncomingFile[] = "incoming";

// Whether a map in `state` takes writes (Ingest, LastSequence).
inline bool TakesWrites(MoveState state) { return state == MoveState::kServing || state == MoveState::kCopying; }

// A batch of a move's tail: its place in the source's log and its EncodeBatch bytes.
struct TailRecord {
  uint64_t lsn = 0;
  std::string batch;
  bool operator==(const TailRecord&) const = default;
};

// The status writes get while a map moves (Unavailable: clients resend, and the proxy takes their
// retries to the new owner once it routes there).
absl::Status MovingError(const std::string& map);

class MapStore {
 public:
  using AckCallback = std::function<void(absl::StatusOr<BatchAck>)>;

  static absl::StatusOr<std::unique_ptr<MapStore>> Open(const MapInfo& info, const std::string& dir,
                                                        const StoreOptions& options);
  virtual ~MapStore() = default;

  virtual const MapInfo& info() const = 0;
  virtual const model::ModelSettings& settings() const = 0;

  // --- writes ---
  // Validates and queues; `done` runs (on the committer thread) once the batch is durable and
  // applied, or refused as a whole (an ack whose `error` is set: nothing applied, the map goes on),
  // or failed (an error status: the map refuses writes from now on). An error returned here means
  // `done` will not run: the batch is unusable (InvalidArgument, OutOfRange), the queue is full
  // (IsQueueFull), the map is closing (Unavailable) or refuses writes (WriteError()).
  virtual absl::Status Submit(ObservationBatch batch, AckCallback done) = 0;
  // Submit and wait. A batch refused as a whole comes back as its ack's error.
  virtual absl::StatusOr<BatchAck> Write(ObservationBatch batch) = 0;
  // Runs `f` once when the queue can take a batch of `observations` — by the same rule Submit
  // applies — or the map stops taking writes (closing, or a latched error: then Submit tells why),
  // on a store thread, or at once when either holds now. A streaming handler whose Submit was
  // refused stops reading and resumes from here, instead of polling.
  virtual void OnRoom(uint64_t observations, std::function<void()> f) = 0;
  // The highest sequence of `writer` logged in this map (so applied, or to be applied before any
  // later batch), 0 when none: where a writer that lost its count continues.
  virtual uint64_t LastSequence(uint64_t writer) const = 0;
  // Checkpoints now and waits.
  virtual absl::Status Checkpoint() = 0;
  // The update job's core (Shard::BeginPublication): republishes P, with its best order, of every
  // dynamic state observed since its last publication; logged so that recovery repeats it at the
  // same point among the batches. It is served a slice at a time between the batches that arrive
  // meanwhile, which are acknowledged as usual; checkpoints wait for it. Waits; returns the states
  // published. `progress(done, total)` is called from time to time while the shards publish.
  virtual absl::StatusOr<uint64_t> PublishModels(
      std::function<void(uint64_t, uint64_t)> progress = nullptr) = 0;
  // Keeps what an update job did, for Stats(), in <dir>/last_update (replaced atomically).
  virtual absl::Status RecordUpdate(const UpdateRecord& record) = 0;
  // Stops accepting writes, finishes the queued ones and checkpoints. Idempotent.
  virtual absl::Status Close() = 0;
  // OK, or the error that stopped all writes to the map (a failed log sync, commit or checkpoint:
  // latched, so that nothing is acknowledged that might not be durable; no checkpoint or backup
  // is written after it either — the log holds every applied batch). Reads still work.
  virtual absl::Status WriteError() const = 0;

  // --- moves (docs/fleet.md, "Moving a map") ---
  // From now on Submit and PublishModels refuse with MovingError, and OnRoom's waiters are woken
  // to learn it; returns once every batch submitted before is applied and acknowledged (a
  // checkpoint), so that a backup taken next holds every acknowledged batch. Not kept across a
  // reopen. Idempotent; OK once moved.
  virtual absl::Status StopWrites() = 0;
  // Takes writes again; FailedPrecondition once moved.
  virtual absl::Status ResumeWrites() = 0;
  // The move's commit: writes stay refused, across reopens (<dir>/moved_to, replaced atomically),
  // until the map is deleted. FailedPrecondition unless writes are stopped (or it is moved already:
  // then OK, `to` kept as first given).
  virtual absl::Status MarkMoved(const std::string& to) = 0;
  virtual MoveStatus Move() const = 0;

  // --- online moves: the snapshot while writes go on, then the tail (docs/fleet.md) ---
  // From now on every batch logged is also recorded in memory (at most max_tail_bytes), and
  // PublishModels is refused (MovingError): writes go on. Then Backup's `lsn` says where the
  // snapshot is, and, once StopWrites has returned, Tail gives the batches logged after it.
  // FailedPrecondition unless serving or copying (a capture in progress starts again, empty).
  // Ended by ResumeWrites (back to serving), MarkMoved or a reopen.
  virtual absl::Status StartTail() = 0;
  // The batches logged after `after`, in log order. FailedPrecondition unless StartTail was called
  // and writes are stopped since, or when the capture was given up (it outgrew max_tail_bytes, an
  // update job published meanwhile, or a storage error latched).
  virtual absl::StatusOr<std::vector<TailRecord>> Tail(uint64_t after) const = 0;
  // For a copy restored kIncoming: applies `tail` (the source's Tail after its snapshot) through
  // the write path — logged, deduplicated, acknowledged — then checkpoints and serves.
  // FailedPrecondition unless kIncoming with snapshot_lsn == `after`; DataLoss when a batch does
  // not decode or is not new (the tail does not continue this snapshot): the copy is not to be used.
  virtual absl::Status ApplyTail(uint64_t after, std::span<const TailRecord> tail) = 0;

  // --- reads ---
  // p at every (time, key): out[i·keys + j] for times[i], keys[j].
  virtual std::vector<float> Predict(std::span<const uint64_t> keys, std::span<const double> times,
                                     const PredictOptions& options) const = 0;
  // p(t) of every cell of a box of a grid, x fastest; unobserved cells 0.5.
  virtual absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options,
                                  std::vector<float>& out) const = 0;
  // The same into memory of the caller's (a response's values, written in place): InvalidArgument
  // unless out holds exactly the box's cells.
  virtual absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options,
                                  std::span<float> out) const = 0;
  // The same quantised, round(255·p) a cell (model::QuantizeProbability: a UINT8 region's wire
  // form), written by the shards as they predict: no float of the box is made.
  virtual absl::Status PredictBox(const CellBox& box, double t, const PredictOptions& options,
                                  std::span<uint8_t> out) const = 0;
  // A box at many times, planned once at `t` (one of the times): which cells vary with time and
  // the others' p. Errors as PredictBox's. The plan holds the models as they are now: a later
  // batch that makes a constant cell vary is not seen by it.
  virtual absl::StatusOr<BoxSeries> PlanBoxSeries(const CellBox& box, double t,
                                                  const PredictOptions& options) const = 0;
  // out[g * n + i] = p(times[g]) of the plan's varying cell i (n of them), bit for bit what
  // PredictBox gives it at times[g]; one phasor table a time, spread over the shards like
  // PredictBox. A few times in one call read each model record once for all of them. `out` is
  // resized to times.size() × n.
  virtual void PredictBoxSeries(const BoxSeries& plan, std::span<const double> times,
                                std::vector<float>& out) const = 0;
  virtual std::optional<StateSnapshot> Snapshot(uint64_t key) const = 0;
  // observed[i]: whether keys[i] was ever observed.
  virtual std::vector<uint8_t> Observed(std::span<const uint64_t> keys) const = 0;
  // Predict and Observed together, in one lookup per key: `observed` is resized to keys.size().
  virtual std::vector<float> PredictWithObserved(std::span<const uint64_t> keys, std::span<const double> times,
                                                 const PredictOptions& options,
                                                 std::vector<uint8_t>& observed) const = 0;
  virtual std::optional<std::pair<std::string, std::string>> Label(uint64_t key) const = 0;
  // Every labelled state (a batch named it or gave it a group), or only those of `group` when it
  // is not empty (NOT_FOUND when no state has that group); in (name, key) order. Linear in the
  // labels: a listing copies them all, as a dashboard's page of a generic map does.
  virtual absl::StatusOr<std::vector<StateLabel>> Labels(const std::string& group) const = 0;
  // The n states of `group` most likely to be 1 at t, most likely first.
  virtual absl::StatusOr<std::vector<std::pair<uint64_t, float>>> TopN(const std::string& group, double t,
                                                                       size_t n,
                                                                       const PredictOptions& options) const = 0;
  virtual MapStats Stats() const = 0;
  // A consistent copy of every shard, the map's info and its last update record into `dir`
  // (created, must be empty). `lsn`, when given, is set to the log position the copy holds every
  // batch up to (and none after).
  // Returns the bytes written.
  virtual absl::StatusOr<uint64_t> Backup(const std::string& dir, uint64_t* lsn = nullptr) = 0;
  // Verifies the map's files while it serves (storage/verify.h). Each shard is read in a forked
  // child process through LMDB's reader table: LMDB allows one environment per file per process,
  // and an abort on a damaged page ends the child, not the daemon. Checkpoints wait meanwhile (as
  // for a backup), so that the shards and the log are read at one position and no log segment is
  // dropped while it is read; batches go on being logged and acknowledged.
  // A shard not read by `deadline` is reported "not verified".
  virtual VerifyReport Verify(absl::Time deadline = absl::InfiniteFuture()) = 0;
};

}  // namespace fremen::storage
