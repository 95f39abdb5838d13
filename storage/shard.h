// One shard of a map: the working models of the states whose bricks hash to it (storage/cell_key.h),
// held in memory in the batch kernels' flat tables, and the LMDB environment they are checkpointed
// into.
//
// A state is first a 16-byte StaticState (never changed); its first change promotes it to a dynamic
// state with a row in each table: float spectrum (RecordArena), published model (CompactModels),
// persistence, order errors (and, on lossless maps, its LosslessHistory). States are found through
// bricks: 512 consecutive keys (an 8×8×8 block of a grid) share one hash lookup, which is what makes
// a box query a walk over arrays rather than a lookup per cell.
//
// On disk (one LMDB environment per shard):
//   static    brick key → version, 64-byte presence bitmap, 16 bytes per present never-changed state
//   dynamic   state key → EncodeStateModel<float> (spectrum, P, persistence, order errors)
//   lossless  state key → LosslessHistory record (lossless maps)
//   wide      state key → the double spectrum body of a state past 2^20 observations (WideBodies)
//   labels    state key → name and group (generic maps)
//   meta      "checkpoint_lsn" → the last log record the checkpoint covers; "dedup" → DedupTable;
//             "touched" → the dynamic states observed since their last publication (delta varints)
// Keys are big-endian so that LMDB's order is key order (Morton order for grids).
//
// Thread-safety: Apply*, PrepareCheckpoint and Publish* are called by one writer at a time (the
// map's applier, or a worker it hands the shard to and waits for: ShardWorkers; WriteCheckpoint
// may run on another thread); readers may call the
// const query methods concurrently with them —
// an internal shared mutex keeps a reader from seeing a half-applied batch. The tables readers see
// are ABSL_GUARDED_BY it: readers hold it shared, the writer changes them holding it exclusively and
// may read them without it (nothing else changes them; WritersHistory is such a read).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "storage/batch.h"
#include "storage/brick_models.h"
#include "storage/brick_region.h"
#include "storage/dedup_table.h"
#include "storage/lmdb/lmdb_env.h"
#include "storage/map_info.h"
#include "storage/model/kernels/compact_models.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/kernels/order_error_table.h"
#include "storage/model/persistence.h"
#include "storage/model/kernels/publication.h"
#include "storage/model/kernels/record_arena.h"
#include "storage/model/kernels/scan_update.h"
#include "storage/model/state_model.h"
#include "storage/model/static_state.h"
#include "storage/model/kernels/wide_bodies.h"
#include "storage/queries.h"
#include "storage/shard_stats.h"

namespace fremen::storage {

// Everything about one scan time that every shard shares: computed once per batch.
struct ScanContext {
  explicit ScanContext(const model::PeriodSet& periods, double t) : table(periods, t), phasors(table) {}
  model::PhasorTable table;
  model::ScanPhasors<float> phasors;
};

// A history's observations of one shard at one time: keys [previous run's end, end).
struct ObservationRun {
  double time;
  uint32_t end;
};

class Shard {
 public:
  // Opens (creating when missing) the shard's environment and loads every state into memory.
  // `widen_records_at`: the observation count at which a dynamic state's float spectrum is widened
  // to double (model/wide_bodies.h); tests lower it.
  static absl::StatusOr<std::unique_ptr<Shard>> Open(const MapInfo& map, const model::ModelSettings& settings,
                                                     const std::string& dir, const LmdbOptions& options,
                                                     uint32_t widen_records_at = model::kCompactRecordLimit);

  // --- writer side ---
  // Folds accepted observations (keys of this shard, values in [0, 1]) taken at the scan's time.
  void Apply(const ScanContext& scan, std::span<const uint64_t> keys, std::span<const float> values);
  // The same for a history's runs, in order, under one lock: a history of one state is a run per
  // observation, so what Apply does once per scan (the lock, the phasors) is here paid per run only
  // where it is needed.
  void ApplyHistory(const model::PeriodSet& periods, std::span<const ObservationRun> runs,
                    std::span<const uint64_t> keys, std::span<const float> values);
  void ApplyLabels(std::span<const StateLabel> labels);
  // --- the update job (docs/update-job.md; storage/shard_publication.cc) ---
  // A publication updates every dynamic state touched (observed) since its own last publication:
  // choose the order with the lowest decayed error and republish P from the spectrum
  // (docs/model.md, "Order selection"); on lossless maps also reconstruct, re-transform, re-select
  // and rebuild O (docs/model.md, "Lossless history"). A state not touched since is left as it is,
  // so a second run without new data changes nothing.
  //
  // It runs in slices between batches: BeginPublication marks the touched states pending, each
  // ContinuePublication publishes some of them, and a batch that observes a pending state publishes
  // it first (in Apply) — so every state is published as it was at BeginPublication, exactly what
  // replaying the publication's log record before the later batches gives.
  //
  // Marks the touched states pending; returns how many. A publication still in progress is
  // finished first.
  size_t BeginPublication();
  // Publishes pending states for about `budget` (at least one block); true when none is left.
  bool ContinuePublication(std::chrono::nanoseconds budget);
  // Pending states handled so far by the current (or last) publication, and their total.
  uint64_t publication_done() const { return publication_cursor_; }
  uint64_t publication_total() const { return publication_list_.size(); }
  // A whole publication at once (recovery's replay, tests); returns the states published.
  // `progress(states done)` is called after every block of states.
  size_t PublishAll(const std::function<void(uint64_t)>& progress = nullptr);
  // A checkpoint writes every state changed since the last one, the dedup table and `lsn` in one
  // durable transaction, in two steps so that the writer stalls only for the first: PrepareCheckpoint encodes
  // every state changed since the last one (with the dedup table, the touched flags and `lsn`) into
  // an image and marks them clean — the writer calls it; WriteCheckpoint puts an image into LMDB in
  // one durable transaction on any thread, while the writer goes on applying batches. Images must
  // be written in the order they were prepared, one at a time. Once a write fails, every later
  // write fails with its error: the failed image's states are clean in memory but not on disk.
  struct CheckpointImage {
    uint64_t lsn = 0;
    std::vector<std::pair<uint64_t, std::string>> dynamic, published, lossless, wide, labels;  // state key → record
    std::vector<std::pair<uint64_t, std::string>> statics;  // brick → StaticBrick, empty = delete it
    std::string touched, dedup;
  };
  CheckpointImage PrepareCheckpoint(uint64_t lsn, const DedupTable& dedup);
  absl::Status WriteCheckpoint(const CheckpointImage& image);
  uint64_t checkpoint_lsn() const { return checkpoint_lsn_; }
  const DedupTable& checkpoint_dedup() const { return checkpoint_dedup_; }

  // --- readers ---
  // p(t) of one state (kUnobservedProbability when never observed).
  float Predict(uint64_t key, const model::PhasorTable& table, const PredictOptions& options) const;
  // Writes p(t) of every cell of `box` in a brick this shard holds into out[index of the cell in
  // the box] (x fastest, then y, then z), unobserved cells of those bricks included, from the
  // bricks' images; other cells are left as they are. T: float, or uint8_t for p quantised
  // (CellValue, storage/brick_region.h). `held` (when not null): held[i] = 1 for each of those
  // bricks, i its number in BoxBricks(box, brick size), so that the caller fills only the others.
  template <typename T>
  void PredictBox(const CellBox& box, const model::PhasorTable& table, const PredictOptions& options, T* out,
                  uint8_t* held = nullptr) const;
  // PredictBox's first half for a box at many times: of the cells of `box` held by this shard,
  // those whose p(t) cannot change with t under `options` (VariesWithTime) get p(t) written into
  // out[index in the box], exactly as PredictBox writes it; the others get dynamic[index] = their
  // dynamic index (and out left as it is), for PredictDynamic. A dynamic index is its state's for
  // the shard's life: dynamic states are only ever added.
  void PredictBoxConstant(const CellBox& box, const model::PhasorTable& table, const PredictOptions& options,
                          float* out, uint32_t* dynamic) const;
  // out[g * stride + at[i]] = p(t_g) of dynamic state dynamic[i] at each tables[g]'s time, as
  // PredictBox gives it (published models through the region kernel together): the second half,
  // at a few times at once, without a lookup per state.
  void PredictDynamic(std::span<const uint32_t> dynamic, std::span<const uint32_t> at,
                      std::span<const model::PhasorTable> tables, const PredictOptions& options, float* out,
                      size_t stride) const;
  std::optional<StateSnapshot> Snapshot(uint64_t key) const;
  // Whether the state was ever observed (cheap: one brick lookup).
  bool Observed(uint64_t key) const;
  // The batched forms, under one lock: for each i, out[at[i]] = Predict(keys[at[i]], ...) /
  // Observed(keys[at[i]]). REQUIRES: every keys[at[i]] is this shard's. Published models go through
  // the region kernel together, as in PredictBox.
  // PredictKeys also sets observed[at[i]] when `observed` is not null (the same lookup).
  void PredictKeys(std::span<const uint64_t> keys, std::span<const uint32_t> at, const model::PhasorTable& table,
                   const PredictOptions& options, float* out, uint8_t* observed = nullptr) const;
  void ObservedKeys(std::span<const uint64_t> keys, std::span<const uint32_t> at, uint8_t* out) const;
  // A generic state's name and group, when labelled.
  std::optional<std::pair<std::string, std::string>> Label(uint64_t key) const;
  ShardStats Stats() const;
  // Calls f(key) for every state held (unordered).
  void ForEachKey(const std::function<void(uint64_t)>& f) const;
  // Calls f(key, name, group) for every labelled state (unordered).
  void ForEachLabel(const std::function<void(uint64_t, const std::string&, const std::string&)>& f) const;

  LmdbEnv& env() { return *env_; }

 private:
  Shard(const MapInfo& map, const model::ModelSettings& settings, std::unique_ptr<LmdbEnv> env,
        uint32_t widen_records_at);

  static constexpr uint32_t kNone = UINT32_MAX;
  // A handle says what predicting a cell needs without touching its slot: kNone (unobserved),
  // kStaticHandle | value (never changed), or the dynamic index.
  static constexpr uint32_t kStaticHandle = 0x80000000u;
  // Slots are allocated 64 at a time per run of 64 keys (a 4×4×4 or 8×8 block), so that the
  // states of neighbouring cells — what one scan touches — sit together in memory.
  static constexpr uint32_t kChunk = 64;
  struct Brick {
    std::array<uint32_t, 512> handles;                 // see kStaticHandle
    std::array<uint32_t, 512 / kChunk> chunk_base;     // first slot of each run of 64 keys, or kNone
  };

  uint32_t FindSlot(uint64_t key) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // The slot of local index i of a brick, or kNone when that cell was never observed.
  uint32_t SlotAt(const Brick& brick, uint32_t local) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // The brick of a key, created when missing. Consecutive calls for one brick cost no hash lookup.
  Brick& BrickFor(uint64_t key) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  uint32_t FindOrAddSlot(uint64_t key) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // The slot a key has or will have (allocating its run of 64), without touching the slot itself.
  uint32_t ReserveSlot(uint64_t key) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // ReserveSlot of every key into slots[i].
  void ReserveSlots(std::span<const uint64_t> keys, uint32_t* slots) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // The only writer of handles, so that a grid's brick images follow them.
  void SetHandle(uint64_t key, uint32_t handle) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_) {
    BrickFor(key).handles[key & 511] = handle;
    if (layout_) images_[cached_brick_index_].Set(layout_->RowMajor(key & 511), handle);
  }
  // Static → dynamic; returns the dynamic index.
  uint32_t Promote(uint32_t slot) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Apply's body for observations at table.time(); `phasors` are the table's, or null to compute
  // them here when a state needs them.
  void ApplyAt(const model::PhasorTable& table, const model::ScanPhasors<float>* phasors,
               std::span<const uint64_t> keys, std::span<const float> values) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Apply's second part: scores and folds the scan's observations of wide states (scan_wide_*).
  void ApplyWide(const model::PhasorTable& table, const model::ScanScoring& scoring)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // What every observation of a dynamic state updates besides its spectrum and order errors.
  void ObserveBesidesSpectrum(uint32_t d, double t, float value) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  uint32_t AddDynamic(uint32_t slot) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // The slot's records change: all of them are written by the next checkpoint.
  void MarkDirty(uint32_t slot) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Only the slot's published model changes: the next checkpoint writes its published record
  // alone, unless something else marks the slot dirty meanwhile.
  void MarkPublishedDirty(uint32_t slot) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // out[g * stride + at[i]] = p(t_g) of the state behind handles[i], for i < handles.size() ≤ 512
  // and each tables[g] (the time t_g): the published models through the region kernel together,
  // the others one by one. The handles are sorted out once for all the times, and their records,
  // read at the first time, are still in cache at the next.
  void PredictHandles(std::span<const uint32_t> handles, const uint32_t* at,
                      std::span<const model::PhasorTable> tables, const PredictOptions& options, float* out,
                      size_t stride) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // A box walked brick by brick (ForEachBoxCell, PredictBox): this shard's bricks in the box, in
  // the box's order, and a cell's index in its brick as the sum of its axes' bits, spread (three
  // lookups per cell instead of a Morton encoding).
  struct BoxWalk {
    struct BoxBrick {
      const Brick* brick;
      const BrickImage* image;
      uint32_t bx, by, bz;
    };
    std::array<uint32_t, 3> brick_size;
    std::array<uint32_t, 32> spread_x{}, spread_y{}, spread_z{};
    std::vector<BoxBrick> bricks;
    // A brick's handles (2 KB) are cold: the walk fetches the next brick's while it visits one.
    void PrefetchHandles(size_t b) const;
    // The same for the next brick's image (512 bytes and its dynamic cells).
    void PrefetchImage(size_t b) const;
    // The cells of `box` in brick b: [lo[a], hi[a]) on each axis a.
    struct Cells {
      std::array<uint32_t, 3> lo, hi;
    };
    Cells CellsIn(const CellBox& box, size_t b) const;
  };
  BoxWalk WalkOf(const CellBox& box) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // Calls visit(handle, index in the box) for every cell of `box` held by this shard, brick by
  // brick, and end_brick() after each brick's cells.
  template <typename Visit, typename EndBrick>
  void ForEachBoxCell(const CellBox& box, Visit visit, EndBrick end_brick) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // Whether p(t) of the state behind a handle may change with t under `options`: not for an
  // unobserved cell (0.5), a never changed one (its value; persistence agrees), a dynamic state
  // without a published model (the mean of its observations) or with one used at order 0 (α0) —
  // unless persistence blends in the last observation, which decays with t.
  bool VariesWithTime(uint32_t handle, const PredictOptions& options) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // p(t) of the state behind a handle (see kStaticHandle).
  float PredictHandle(uint32_t handle, const model::PhasorTable& table, const PredictOptions& options) const
      ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // out[i] = p(t) of dynamic state dynamic[i], each with a published model: the region kernel
  // (model/region_predict.h, what the benchmark measures), then persistence when asked for.
  void PredictPublished(std::span<const uint32_t> dynamic, const model::PhasorTable& table,
                        const PredictOptions& options, float* out) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // Publishes one dynamic state (see BeginPublication) and clears its flags; `history_updated`:
  // the caller has updated its lossless history already (outside the lock).
  void PublishState(uint32_t dynamic, bool history_updated = false) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // The touched states' keys for the checkpoint (delta varints, in key order), and back.
  std::string EncodeTouched() const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  absl::Status DecodeTouched(std::string_view bytes) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  model::CompactStateModel ModelOf(uint32_t dynamic) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // ModelOf without the published model: what the dynamic record holds (see kPublishedDb).
  model::CompactStateModel UnpublishedModelOf(uint32_t dynamic) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  // The published model of a dynamic state that has one.
  model::PublishedModel PublishedOf(uint32_t dynamic) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  void StoreModel(uint32_t dynamic, const model::CompactStateModel& model) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Not analysed: Open calls it before the shard is shared, when there is nothing to lock against.
  absl::Status Load() ABSL_NO_THREAD_SAFETY_ANALYSIS;
  // A copy of a lossless history, for the writer only, without the lock: no other thread changes
  // the tables, so the writer reads them as they are (not analysed: the analysis knows no such role).
  model::LosslessHistory WritersHistory(uint32_t dynamic) const ABSL_NO_THREAD_SAFETY_ANALYSIS {
    return lossless_histories_[dynamic];
  }

  const MapInfo map_;
  const model::ModelSettings& settings_;
  const bool lossless_;
  const GridKeys grid_keys_;
  std::unique_ptr<LmdbEnv> env_;
  mutable base::SharedMutex mutex_;

  absl::flat_hash_map<uint64_t, uint32_t> bricks_ ABSL_GUARDED_BY(mutex_);  // brick → index into bricks_data_
  std::vector<Brick> brick_data_ ABSL_GUARDED_BY(mutex_);
  // A grid's bricks as regions read them (storage/brick_region.h), images_[i] for brick_data_[i],
  // kept by SetHandle; none for a generic map.
  const std::optional<BrickLayout> layout_;
  std::vector<BrickImage> images_ ABSL_GUARDED_BY(mutex_);
  // The same as bricks_ as an array, brick → index or kNone, for a grid whose keys span at most
  // kMaxDirectoryBricks bricks (a 2-D grid up to 16k × 16k cells; empty otherwise): a batched
  // Predict's scattered cells are looked up without a hash and a probe each (docs/performance.md,
  // "Batched Predict"). Kept by BrickFor with bricks_.
  static constexpr uint64_t kMaxDirectoryBricks = uint64_t{1} << 20;
  std::vector<uint32_t> brick_directory_ ABSL_GUARDED_BY(mutex_);
  // The index of `brick` in brick_data_, or -1: from the directory when there is one.
  int64_t DirectoryLookup(uint64_t brick) const ABSL_SHARED_LOCKS_REQUIRED(mutex_) {
    const uint32_t index = brick < brick_directory_.size() ? brick_directory_[brick] : kNone;
    return index == kNone ? -1 : static_cast<int64_t>(index);
  }
  uint64_t cached_brick_ = UINT64_MAX;  // BrickFor's last brick and its index
  uint32_t cached_brick_index_ = 0;
  // Per slot.
  // Per slot, everything the write path touches in one 32-byte record (one cache line access).
  struct Slot {
    model::StaticState static_state;
    uint64_t key = 0;
    uint32_t dynamic = kNone;  // kNone while static
    uint8_t dirty = 0;         // kDirtyAll and kDirtyPublished bits: what the next checkpoint writes
    uint8_t observed = 0;      // a slot of an allocated run whose cell has not been seen is unused
  };
  static_assert(sizeof(Slot) == 32);
  static constexpr uint8_t kDirtyAll = 1, kDirtyPublished = 2;
  std::vector<Slot> slots_ ABSL_GUARDED_BY(mutex_);
  std::vector<uint32_t> dirty_slots_;
  // Per dynamic state.
  std::vector<uint32_t> slot_of_ ABSL_GUARDED_BY(mutex_);
  model::RecordArena spectra_ ABSL_GUARDED_BY(mutex_);
  // Double bodies of the spectra with more observations than float keeps accurately.
  model::WideBodies wide_ ABSL_GUARDED_BY(mutex_);
  const uint32_t widen_at_;
  model::CompactModels models_ ABSL_GUARDED_BY(mutex_);
  // Counts the changes to records of models_ that were published (a publication, a restore): a
  // BrickModels copy made at another count is out of date. New records and first publications do
  // not count: the copy answers the cells it did not copy from models_ itself.
  uint64_t models_generation_ ABSL_GUARDED_BY(mutex_) = 0;
  // Bumps models_generation_ if record d is published (before the caller changes it).
  void BeforeModelChange(uint32_t d) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_) {
    if (models_.published(d)) ++models_generation_;
  }
  // The region's copy of the models brick by brick, made when first asked for after a change (not
  // while a publication is under way, which would make it out of date again at each slice); null
  // when there is none to use (a generic map, or an out-of-date copy during a publication).
  std::shared_ptr<const BrickModels> RegionModels() const ABSL_SHARED_LOCKS_REQUIRED(mutex_)
      ABSL_LOCKS_EXCLUDED(region_models_mutex_);
  mutable base::Mutex region_models_mutex_ ABSL_ACQUIRED_AFTER(mutex_);
  mutable std::shared_ptr<const BrickModels> region_models_ ABSL_GUARDED_BY(region_models_mutex_);
  std::atomic<bool> publishing_{false};  // between BeginPublication and the end of its last slice
  model::OrderErrorTable errors_ ABSL_GUARDED_BY(mutex_);
  std::vector<model::Persistence> persistence_ ABSL_GUARDED_BY(mutex_);
  std::vector<model::LosslessHistory> lossless_histories_ ABSL_GUARDED_BY(mutex_);
  // Per dynamic state: kTouched (observed since its last publication; checkpointed as the meta
  // record "touched") and kPending (awaiting the publication in progress). Writer only.
  static constexpr uint8_t kTouched = 1, kPending = 2;
  std::vector<uint8_t> publish_flags_;
  // The publication in progress: the states it marked pending and how far it has got. Writer only.
  std::vector<uint32_t> publication_list_;
  size_t publication_cursor_ = 0;
  model::Publisher publisher_;
  model::CompactSpectrum publish_scratch_;
  // Generic maps' labels.
  absl::flat_hash_map<uint64_t, std::pair<std::string, std::string>> labels_ ABSL_GUARDED_BY(mutex_);
  std::vector<uint64_t> dirty_labels_;
  // Scratch of Apply.
  std::vector<uint32_t> scan_slots_;
  std::vector<uint32_t> scan_cells_;
  std::vector<float> scan_values_;
  std::vector<uint32_t> scan_wide_cells_;
  std::vector<float> scan_wide_values_;
  // Scratch of ApplyHistory: a run's table and, when needed, its float phasors.
  std::optional<model::PhasorTable> run_table_;
  model::ScanPhasors<float> run_phasors_;

  uint64_t checkpoint_lsn_ = 0;  // of the last image prepared
  base::Mutex checkpoint_write_mutex_;
  absl::Status checkpoint_write_error_ ABSL_GUARDED_BY(checkpoint_write_mutex_);
  DedupTable checkpoint_dedup_;
};

}  // namespace fremen::storage
