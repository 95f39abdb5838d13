#include "storage/shard.h"

#include <algorithm>
#include <cstring>
#include <optional>

#include "absl/strings/str_cat.h"
#include "storage/brick_region.h"
#include "storage/cell_key.h"
#include "storage/model/kernels/publication.h"
#include "storage/model/record_codec.h"
#include "storage/model/kernels/region_predict.h"
#include "storage/model/kernels/scan_update.h"
#include "storage/shard_records.h"
#include "storage/static_bricks.h"

namespace fremen::storage {

namespace {

using shard_records::kDedupKey;
using shard_records::kDynamicDb;
using shard_records::kPublishedDb;
using shard_records::kLabelsDb;
using shard_records::kLosslessDb;
using shard_records::kLsnKey;
using shard_records::kMetaDb;
using shard_records::kStaticDb;
using shard_records::kTouchedKey;
using shard_records::kWideDb;

std::span<const uint8_t> Bytes(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }
std::string_view View(std::span<const uint8_t> b) { return {reinterpret_cast<const char*>(b.data()), b.size()}; }

absl::Status WithKey(const absl::Status& s, const char* family, uint64_t key) {
  return absl::Status(s.code(), absl::StrCat(family, " record of state ", key, ": ", s.message()));
}

}  // namespace

Shard::Shard(const MapInfo& map, const model::ModelSettings& settings, std::unique_ptr<LmdbEnv> env,
             uint32_t widen_records_at)
    : map_(map),
      settings_(settings),
      lossless_(map.lossless_sampling_period > 0),
      grid_keys_(map.grid.keys()),
      env_(std::move(env)),
      layout_(map.kind == MapKind::kGrid ? std::optional<BrickLayout>(grid_keys_) : std::nullopt),
      spectra_(settings.periods.size()),
      wide_(settings.periods.size()),
      widen_at_(widen_records_at),
      models_(settings.max_order),
      errors_(settings.max_order),
      publisher_(settings.periods, settings.max_order),
      publish_scratch_(settings.periods.size()) {
  if (map.kind == MapKind::kGrid && map.grid.size[0] > 0 && map.grid.size[1] > 0 && map.grid.size[2] > 0) {
    // Morton keys grow with each index, so the last cell has the largest key.
    const uint64_t last = BrickOf(grid_keys_.Key(map.grid.size[0] - 1, map.grid.size[1] - 1, map.grid.size[2] - 1));
    if (last < kMaxDirectoryBricks) brick_directory_.assign(last + 1, kNone);
  }
}

absl::StatusOr<std::unique_ptr<Shard>> Shard::Open(const MapInfo& map, const model::ModelSettings& settings,
                                                   const std::string& dir, const LmdbOptions& options,
                                                   uint32_t widen_records_at) {
  LmdbOptions with_databases = options;
  with_databases.databases = shard_records::AllDatabases();
  auto env = LmdbEnv::Open(dir, with_databases);
  if (!env.ok()) return env.status();
  auto shard = std::unique_ptr<Shard>(new Shard(map, settings, *std::move(env), widen_records_at));
  if (absl::Status loaded = shard->Load(); !loaded.ok()) return loaded;
  return shard;
}

uint32_t Shard::SlotAt(const Brick& brick, uint32_t local) const {
  const uint32_t base = brick.chunk_base[local / kChunk];
  if (base == kNone) return kNone;
  const uint32_t slot = base + local % kChunk;
  return slots_[slot].observed ? slot : kNone;
}

uint32_t Shard::FindSlot(uint64_t key) const {
  const auto it = bricks_.find(BrickOf(key));
  return it == bricks_.end() ? kNone : SlotAt(brick_data_[it->second], key & 511);
}

Shard::Brick& Shard::BrickFor(uint64_t key) {
  const uint64_t brick = BrickOf(key);
  if (brick != cached_brick_) {
    // A known brick of a grid with a directory without hashing: a coherent scan changes brick
    // every row of one (32 cells in 2-D).
    int64_t index = DirectoryLookup(brick);
    if (index < 0) {
      auto [it, inserted] = bricks_.try_emplace(brick, static_cast<uint32_t>(brick_data_.size()));
      if (inserted) {
        if (brick < brick_directory_.size()) brick_directory_[brick] = it->second;
        brick_data_.emplace_back();
        brick_data_.back().handles.fill(kNone);
        brick_data_.back().chunk_base.fill(kNone);
        if (layout_) images_.emplace_back();
      }
      index = it->second;
    }
    cached_brick_ = brick;
    cached_brick_index_ = static_cast<uint32_t>(index);
  }
  return brick_data_[cached_brick_index_];
}

uint32_t Shard::FindOrAddSlot(uint64_t key) {
  const uint32_t slot = ReserveSlot(key);
  slots_[slot].observed = 1;
  return slot;
}

void Shard::ReserveSlots(std::span<const uint64_t> keys, uint32_t* slots) {
  // ReserveSlot's work with its brick looked up once per run of the brick's keys (a coherent
  // scan's neighbours); only a new run of 64 goes out of line.
  uint64_t brick_id = ~uint64_t{0};
  Brick* brick = nullptr;  // valid until the next BrickFor, which alone adds bricks
  for (size_t i = 0; i < keys.size(); ++i) {
    const uint64_t key = keys[i];
    if (BrickOf(key) != brick_id) {
      brick_id = BrickOf(key);
      brick = &BrickFor(key);
    }
    const uint32_t local = key & 511;
    const uint32_t base = brick->chunk_base[local / kChunk];
    slots[i] = base != kNone ? base + local % kChunk : ReserveSlot(key);
  }
}

uint32_t Shard::ReserveSlot(uint64_t key) {
  const uint32_t local = key & 511;
  uint32_t& base = BrickFor(key).chunk_base[local / kChunk];
  if (base == kNone) {
    base = static_cast<uint32_t>(slots_.size());
    slots_.resize(slots_.size() + kChunk);
    for (uint32_t i = 0; i < kChunk; ++i) slots_[base + i].key = (key & ~uint64_t{kChunk - 1}) + i;
  }
  return base + local % kChunk;
}

void Shard::MarkDirty(uint32_t slot) {
  if (!slots_[slot].dirty) dirty_slots_.push_back(slot);
  slots_[slot].dirty |= kDirtyAll;
}

void Shard::MarkPublishedDirty(uint32_t slot) {
  if (!slots_[slot].dirty) dirty_slots_.push_back(slot);
  slots_[slot].dirty |= kDirtyPublished;
}

uint32_t Shard::AddDynamic(uint32_t slot) {
  const uint32_t d = static_cast<uint32_t>(slot_of_.size());
  slot_of_.push_back(slot);
  spectra_.Append();
  models_.Resize(d + 1);
  errors_.Resize(d + 1);
  persistence_.emplace_back();
  publish_flags_.push_back(kTouched);
  if (lossless_) {
    lossless_histories_.push_back(*model::LosslessHistory::Create(map_.lossless_origin, map_.lossless_sampling_period));
  }
  slots_[slot].dynamic = d;
  SetHandle(slots_[slot].key, d);
  return d;
}

uint32_t Shard::Promote(uint32_t slot) {
  const uint32_t d = AddDynamic(slot);
  if (slots_[slot].static_state.count() > 0) {
    model::CompactStateModel promoted(settings_);
    slots_[slot].static_state.Promote(settings_, promoted);
    StoreModel(d, promoted);
  }
  return d;
}

void Shard::StoreModel(uint32_t d, const model::CompactStateModel& m) {
  spectra_.Store(d, m.spectrum());
  // A restored record past the limit is widened again from its float body (see wide_bodies.h).
  if (spectra_.header(d).n >= widen_at_) wide_.Widen(d, spectra_.body(d));
  BeforeModelChange(d);
  if (m.has_published()) {
    models_.Set(d, m.published());
  } else {
    models_.SetUnpublished(d, static_cast<float>(m.spectrum().gamma0()));
  }
  persistence_[d] = m.persistence();
  errors_.Set(d, m.order_errors());
}

model::CompactStateModel Shard::ModelOf(uint32_t d) const {
  model::CompactStateModel m = UnpublishedModelOf(d);
  if (models_.published(d)) m.set_published(PublishedOf(d));
  return m;
}

model::CompactStateModel Shard::UnpublishedModelOf(uint32_t d) const {
  model::CompactStateModel m(settings_);
  spectra_.Load(d, m.mutable_spectrum());
  m.mutable_persistence() = persistence_[d];
  m.mutable_order_errors() = errors_.Get(d);
  return m;
}

model::PublishedModel Shard::PublishedOf(uint32_t d) const {
  const model::CompactModelHeader& h = models_.header(d);
  return model::PublishedModel::Restore(h.alpha0, h.order, models_.Components(d));
}

void Shard::Apply(const ScanContext& scan, std::span<const uint64_t> keys, std::span<const float> values) {
  base::WriterMutexLock lock(&mutex_);
  ApplyAt(scan.table, &scan.phasors, keys, values);
}

void Shard::ApplyHistory(const model::PeriodSet& periods, std::span<const ObservationRun> runs,
                         std::span<const uint64_t> keys, std::span<const float> values) {
  if (runs.empty()) return;
  base::WriterMutexLock lock(&mutex_);
  if (!run_table_) run_table_.emplace(periods, runs.front().time);
  uint32_t begin = 0;
  for (const ObservationRun& run : runs) {
    run_table_->Reset(periods, run.time);
    ApplyAt(*run_table_, nullptr, keys.subspan(begin, run.end - begin), values.subspan(begin, run.end - begin));
    begin = run.end;
  }
}

void Shard::ApplyAt(const model::PhasorTable& table, const model::ScanPhasors<float>* phasors,
                    std::span<const uint64_t> keys, std::span<const float> values) {
  const double t = table.time();
  scan_cells_.clear();
  scan_values_.clear();
  // Two passes: first every key's slot (one brick lookup per run of keys), then the states, with
  // the slot records fetched a few cells ahead: a scan's slots are cold, and a miss per cell would
  // cost more than all the arithmetic. 24 cells ahead: a static cell takes a few nanoseconds, less
  // than a miss to memory, and at 8 ahead the slot's first load still stalled (the office load:
  // 37 % of this function's samples on that load at 8 ahead, 25 % at 24; docs/performance.md).
  scan_slots_.resize(keys.size());
  ReserveSlots(keys, scan_slots_.data());
  constexpr size_t kAhead = 24;
  const size_t n = keys.size();
  for (size_t i = 0; i < n; ++i) {
    // Most cells of a mostly static map: a never-changed state seen before, observed again with
    // its value and not before its last observation. StaticState::Observe's result for that case,
    // without its branches (equal to the bit: the span from the same subtraction), in a loop of
    // its own over the run of such cells, so that it keeps its few values in registers; it stops
    // at the first other cell, which the body below takes, in the scan's order.
    if (!lossless_) {
      Slot* const slots = slots_.data();  // nothing in this loop resizes slots_
      const uint32_t* const scan_slots = scan_slots_.data();
      for (; i < n; ++i) {
        if (i + kAhead < n) __builtin_prefetch(&slots[scan_slots[i + kAhead]], 1, 3);
        Slot& cell = slots[scan_slots[i]];
        model::StaticState& state = cell.static_state;
        const uint32_t count_value = state.count_value;
        if (cell.dynamic != kNone || count_value < 2 || values[i] != static_cast<float>(count_value & 1u) ||
            t < state.t_last()) {
          break;
        }
        cell.observed = 1;
        if (!(cell.dirty & kDirtyAll)) [[unlikely]] MarkDirty(scan_slots[i]);
        state.span = static_cast<float>(t - state.t_first);
        state.count_value = count_value + 2;
      }
      if (i == n) break;
    }
    if (i + kAhead < n) __builtin_prefetch(&slots_[scan_slots_[i + kAhead]], 1, 3);
    const uint32_t slot = scan_slots_[i];
    Slot& cell = slots_[slot];
    cell.observed = 1;
    MarkDirty(slot);
    uint32_t d = cell.dynamic;
    if (d == kNone) {
      model::StaticState& state = cell.static_state;
      if (!lossless_ && state.Accepts(values[i])) {
        // Only a state's first observation sets its handle: later ones repeat the same value.
        if (state.count() == 0) SetHandle(keys[i], kStaticHandle | (values[i] == 1.0f ? 1u : 0u));
        state.Observe(t, values[i]);
        continue;
      }
      d = Promote(slot);
    } else {
      // A state the publication in progress has not reached: publish it as it was first.
      if (publish_flags_[d] & kPending) PublishState(d);
      publish_flags_[d] |= kTouched;
    }
    if (wide_.wide(d)) {
      scan_wide_cells_.push_back(d);
      scan_wide_values_.push_back(values[i]);
    } else {
      scan_cells_.push_back(d);
      scan_values_.push_back(values[i]);
    }
  }
  const model::ScanScoring scoring{&models_, &errors_, settings_.criterion, settings_.error_half_life};
  if (!scan_cells_.empty()) {
    if (phasors == nullptr) {
      run_phasors_.Reset(table);
      phasors = &run_phasors_;
    }
    model::ScoreAndApplyScan(spectra_, scoring, table, *phasors, scan_cells_, scan_values_);
  }
  ApplyWide(table, scoring);
  for (size_t j = 0; j < scan_cells_.size(); ++j) {
    const uint32_t d = scan_cells_[j];
    if (spectra_.header(d).n >= widen_at_) wide_.Widen(d, spectra_.body(d));
    ObserveBesidesSpectrum(d, t, scan_values_[j]);
  }
}

void Shard::ObserveBesidesSpectrum(uint32_t d, double t, float value) {
  persistence_[d].Observe(t, value);
  // The batch was validated against the map's lossless origin, so Add cannot fail on time.
  if (lossless_) (void)lossless_histories_[d].Add(t, value);
}

void Shard::ApplyWide(const model::PhasorTable& table, const model::ScanScoring& scoring) {
  if (scan_wide_cells_.empty()) return;
  const double t = table.time();
  // Scored against the published P before the fold, as every observation is (prequential).
  model::ScoreScan(scoring, table, scan_wide_cells_, scan_wide_values_);
  for (size_t j = 0; j < scan_wide_cells_.size(); ++j) {
    const uint32_t d = scan_wide_cells_[j];
    wide_.Fold(d, spectra_.header(d), spectra_.body(d), table, scan_wide_values_[j]);
    ObserveBesidesSpectrum(d, t, scan_wide_values_[j]);
  }
  scan_wide_cells_.clear();
  scan_wide_values_.clear();
}

void Shard::ApplyLabels(std::span<const StateLabel> labels) {
  base::WriterMutexLock lock(&mutex_);
  for (const StateLabel& label : labels) {
    labels_[label.key] = {label.name, label.group};
    dirty_labels_.push_back(label.key);
  }
}

float Shard::PredictHandle(uint32_t handle, const model::PhasorTable& table, const PredictOptions& options) const {
  if (handle == kNone) return kUnobservedProbability;
  if (handle & kStaticHandle) return static_cast<float>(handle & 1u);  // persistence agrees: s(t_l) = value
  const uint32_t d = handle;
  float p;
  if (models_.published(d)) {
    PredictPublished({&d, 1}, table, options, &p);
    return p;
  }
  const model::SpectrumHeader& sh = spectra_.header(d);
  p = sh.n > 0 ? static_cast<float>(sh.sum_s / sh.n) : kUnobservedProbability;
  if (options.persistence && settings_.persistence) {
    p = static_cast<float>(persistence_[d].Predict(table.time(), p));
  }
  return p;
}

void Shard::PredictPublished(std::span<const uint32_t> dynamic, const model::PhasorTable& table,
                             const PredictOptions& options, float* out) const {
  model::PredictRecords(models_, dynamic, table, options.order, out);
  if (options.persistence && settings_.persistence) {
    for (size_t i = 0; i < dynamic.size(); ++i) {
      out[i] = static_cast<float>(persistence_[dynamic[i]].Predict(table.time(), out[i]));
    }
  }
}

float Shard::Predict(uint64_t key, const model::PhasorTable& table, const PredictOptions& options) const {
  base::ReaderMutexLock lock(&mutex_);
  const auto it = bricks_.find(BrickOf(key));
  if (it == bricks_.end()) return kUnobservedProbability;
  return PredictHandle(brick_data_[it->second].handles[key & 511], table, options);
}

namespace {

// The brick of consecutive keys is usually the same (a scan's cells, a region's rows): one hash
// lookup per change of brick.
class BrickLookup {
 public:
  template <typename Map>
  int64_t operator()(const Map& bricks, uint64_t brick) {
    if (brick != brick_) {
      const auto it = bricks.find(brick);
      brick_ = brick;
      index_ = it == bricks.end() ? -1 : static_cast<int64_t>(it->second);
    }
    return index_;
  }

 private:
  uint64_t brick_ = UINT64_MAX;
  int64_t index_ = -1;
};

}  // namespace

void Shard::PredictKeys(std::span<const uint64_t> keys, std::span<const uint32_t> at,
                        const model::PhasorTable& table, const PredictOptions& options, float* out,
                        uint8_t* observed) const {
  base::ReaderMutexLock lock(&mutex_);
  constexpr size_t kBatch = 512;
  std::array<int64_t, kBatch> bricks;
  std::array<uint32_t, kBatch> handles;
  // kBatch positions at a time, in passes that each prefetch what the next one reads: a batch of
  // scattered states (a dashboard's, a fleet's) misses the cache three times per state — the brick
  // table, the brick's handles, the model record — and the passes overlap those misses instead of
  // taking them one after another. Published models then go through the region kernel together.
  for (size_t begin = 0; begin < at.size(); begin += kBatch) {
    const size_t count = std::min(at.size() - begin, kBatch);
    const uint32_t* positions = at.data() + begin;
    if (brick_directory_.empty()) {
      for (size_t k = 0; k < count; ++k) bricks_.prefetch(BrickOf(keys[positions[k]]));
      BrickLookup lookup;
      for (size_t k = 0; k < count; ++k) bricks[k] = lookup(bricks_, BrickOf(keys[positions[k]]));
    } else {
      for (size_t k = 0; k < count; ++k) bricks[k] = DirectoryLookup(BrickOf(keys[positions[k]]));
    }
    for (size_t k = 0; k < count; ++k) {
      if (bricks[k] >= 0) __builtin_prefetch(&brick_data_[bricks[k]].handles[keys[positions[k]] & 511]);
    }
    for (size_t k = 0; k < count; ++k) {
      handles[k] = bricks[k] < 0 ? kNone : brick_data_[bricks[k]].handles[keys[positions[k]] & 511];
      if (handles[k] != kNone && !(handles[k] & kStaticHandle)) model::PrefetchForRead(models_.record(handles[k]), 64);
    }
    if (observed) {
      for (size_t k = 0; k < count; ++k) observed[positions[k]] = handles[k] != kNone;
    }
    PredictHandles({handles.data(), count}, positions, {&table, 1}, options, out, /*stride=*/0);
  }
}

void Shard::ObservedKeys(std::span<const uint64_t> keys, std::span<const uint32_t> at, uint8_t* out) const {
  base::ReaderMutexLock lock(&mutex_);
  BrickLookup lookup;
  for (const uint32_t i : at) {
    const int64_t brick = lookup(bricks_, BrickOf(keys[i]));
    out[i] = brick >= 0 && brick_data_[brick].handles[keys[i] & 511] != kNone;
  }
}

Shard::BoxWalk Shard::WalkOf(const CellBox& box) const {
  BoxWalk walk;
  const std::array<uint32_t, 3> bs = walk.brick_size = grid_keys_.brick_size();
  for (uint32_t i = 0; i < 32; ++i) {
    if (i < bs[0]) walk.spread_x[i] = grid_keys_.LocalIndex(i, 0, 0);
    if (i < bs[1]) walk.spread_y[i] = grid_keys_.LocalIndex(0, i, 0);
    if (i < bs[2]) walk.spread_z[i] = grid_keys_.LocalIndex(0, 0, i);
  }
  // One lookup per brick: in the directory, or the hash table when the grid has none.
  for (uint32_t bz = box.lo[2] / bs[2]; bz <= (box.hi[2] - 1) / bs[2]; ++bz) {
    for (uint32_t by = box.lo[1] / bs[1]; by <= (box.hi[1] - 1) / bs[1]; ++by) {
      for (uint32_t bx = box.lo[0] / bs[0]; bx <= (box.hi[0] - 1) / bs[0]; ++bx) {
        const uint64_t brick = BrickOf(grid_keys_.Key(bx * bs[0], by * bs[1], bz * bs[2]));
        int64_t index = DirectoryLookup(brick);
        if (index < 0 && brick_directory_.empty()) {
          const auto it = bricks_.find(brick);
          if (it != bricks_.end()) index = it->second;
        }
        if (index < 0) continue;
        const BrickImage* image = layout_ ? &images_[index] : nullptr;
        walk.bricks.push_back({&brick_data_[index], image, bx, by, bz});
      }
    }
  }
  return walk;
}

void Shard::BoxWalk::PrefetchHandles(size_t b) const {
  if (b < bricks.size()) model::PrefetchForRead(bricks[b].brick->handles.data(), sizeof(Brick::handles));
}

void Shard::BoxWalk::PrefetchImage(size_t b) const {
  if (b >= bricks.size()) return;
  const BrickImage& image = *bricks[b].image;
  model::PrefetchForRead(image.bytes(), 512);
  model::PrefetchForRead(image.dynamic().data(), image.dynamic().size() * sizeof(BrickImage::DynamicCell));
}

Shard::BoxWalk::Cells Shard::BoxWalk::CellsIn(const CellBox& box, size_t b) const {
  const std::array<uint32_t, 3> at = {bricks[b].bx, bricks[b].by, bricks[b].bz};
  Cells cells;
  for (int a = 0; a < 3; ++a) {
    cells.lo[a] = std::max(box.lo[a], at[a] * brick_size[a]);
    cells.hi[a] = std::min(box.hi[a], (at[a] + 1) * brick_size[a]);
  }
  return cells;
}

template <typename Visit, typename EndBrick>
void Shard::ForEachBoxCell(const CellBox& box, Visit visit, EndBrick end_brick) const {
  const uint64_t nx = box.hi[0] - box.lo[0], ny = box.hi[1] - box.lo[1];
  const BoxWalk walk = WalkOf(box);
  const std::array<uint32_t, 3> bs = walk.brick_size;
  const uint32_t mask_x = bs[0] - 1;  // brick sides are powers of two
  walk.PrefetchHandles(0);
  for (size_t b = 0; b < walk.bricks.size(); ++b) {
    walk.PrefetchHandles(b + 1);
    const Brick* brick = walk.bricks[b].brick;
    const BoxWalk::Cells c = walk.CellsIn(box, b);
    for (uint32_t z = c.lo[2]; z < c.hi[2]; ++z) {
      for (uint32_t y = c.lo[1]; y < c.hi[1]; ++y) {
        // The index of cell (0, y, z) in the box (x = lo.x is at row + lo.x).
        const uint64_t row = ((z - box.lo[2]) * ny + (y - box.lo[1])) * nx - box.lo[0];
        const uint32_t yz = walk.spread_y[y & (bs[1] - 1)] | walk.spread_z[z & (bs[2] - 1)];
        for (uint32_t x = c.lo[0]; x < c.hi[0]; ++x) {
          const uint32_t handle = brick->handles[yz | walk.spread_x[x & mask_x]];
          if (handle != kNone) visit(handle, row + x);
        }
      }
    }
    end_brick();
  }
}

bool Shard::VariesWithTime(uint32_t handle, const PredictOptions& options) const {
  if (handle == kNone || (handle & kStaticHandle)) return false;
  if (options.persistence && settings_.persistence) return true;
  if (!models_.published(handle)) return false;
  const int order = options.order < 0 ? models_.header(handle).order : std::min(options.order, models_.max_order());
  return order > 0;
}

void Shard::PredictDynamic(std::span<const uint32_t> dynamic, std::span<const uint32_t> at,
                           std::span<const model::PhasorTable> tables, const PredictOptions& options, float* out,
                           size_t stride) const {
  base::ReaderMutexLock lock(&mutex_);
  constexpr size_t kBatch = 512;
  for (size_t begin = 0; begin < dynamic.size(); begin += kBatch) {
    const size_t count = std::min(dynamic.size() - begin, kBatch);
    PredictHandles(dynamic.subspan(begin, count), at.data() + begin, tables, options, out, stride);
  }
}

void Shard::PredictHandles(std::span<const uint32_t> handles, const uint32_t* at,
                           std::span<const model::PhasorTable> tables, const PredictOptions& options, float* out,
                           size_t stride) const {
  if (tables.empty()) return;
  std::array<uint32_t, 512> published, published_at, other, other_at;
  std::array<float, 512> predicted;
  size_t n = 0, m = 0;
  // The other states at the first time right away (a single time, the common case, keeps no list).
  const bool more_times = tables.size() > 1;
  for (size_t k = 0; k < handles.size(); ++k) {
    const uint32_t handle = handles[k];
    if (handle != kNone && !(handle & kStaticHandle) && models_.published(handle)) {
      published[n] = handle;
      published_at[n++] = at[k];
    } else {
      out[at[k]] = PredictHandle(handle, tables[0], options);
      if (more_times) {
        other[m] = handle;
        other_at[m++] = at[k];
      }
    }
  }
  for (size_t g = 0; g < tables.size(); ++g) {
    float* const frame = out + g * stride;
    if (g > 0) {
      for (size_t j = 0; j < m; ++j) frame[other_at[j]] = PredictHandle(other[j], tables[g], options);
    }
    PredictPublished({published.data(), n}, tables[g], options, predicted.data());
    for (size_t j = 0; j < n; ++j) frame[published_at[j]] = predicted[j];
  }
}

void Shard::PredictBoxConstant(const CellBox& box, const model::PhasorTable& table, const PredictOptions& options,
                               float* out, uint32_t* dynamic) const {
  if (box.cell_count() == 0) return;
  base::ReaderMutexLock lock(&mutex_);
  // As PredictBox: the published models through the region kernel together, a brick at a time, so
  // that a constant cell's value is PredictBox's bit for bit.
  std::array<uint32_t, 512> published;
  std::array<uint64_t, 512> published_cells;
  std::array<float, 512> predicted;
  size_t n = 0;
  ForEachBoxCell(
      box,
      [&](uint32_t handle, uint64_t i) ABSL_NO_THREAD_SAFETY_ANALYSIS {  // under the lock above
        if (VariesWithTime(handle, options)) {
          dynamic[i] = handle;
        } else if (!(handle & kStaticHandle) && models_.published(handle)) {
          published[n] = handle;
          published_cells[n++] = i;
        } else {
          out[i] = PredictHandle(handle, table, options);
        }
      },
      [&]() ABSL_NO_THREAD_SAFETY_ANALYSIS {
        PredictPublished({published.data(), n}, table, options, predicted.data());
        for (size_t j = 0; j < n; ++j) out[published_cells[j]] = predicted[j];
        n = 0;
      });
}

std::shared_ptr<const BrickModels> Shard::RegionModels() const {
  base::MutexLock lock(&region_models_mutex_);
  if (region_models_ == nullptr || region_models_->generation() != models_generation_) {
    if (publishing_) return nullptr;
    // Under the shared lock: no writer changes images_ or models_ while the copy is made.
    region_models_ = std::make_shared<const BrickModels>(images_, models_, models_generation_);
  }
  return region_models_;
}

// PredictRegion's hot path keeps its own loop over the bricks' images (storage/brick_region.h),
// not PredictBoxConstant's walk over handles (ForEachBoxCell): a cell's handle read and turned into
// p was most of a 1M-cell region's time.
template <typename T>
void Shard::PredictBox(const CellBox& box, const model::PhasorTable& table, const PredictOptions& options, T* out,
                       uint8_t* held) const {
  if (box.cell_count() == 0) return;
  base::ReaderMutexLock lock(&mutex_);
  const uint64_t nx = box.hi[0] - box.lo[0], ny = box.hi[1] - box.lo[1];
  const BoxWalk walk = WalkOf(box);
  const std::array<uint32_t, 3> bs = walk.brick_size;
  // The cells whose state has a published model — nearly all dynamic ones, on a map in use — go
  // through the region kernel together, a brick at a time: from the brick's copy of them
  // (BrickModels, when it covers them), else their records prefetched as they are gathered; the
  // others are answered one by one. They are told apart by the published bits kept
  // beside the records (CompactModels::published), which read no record (a miss per dynamic cell,
  // one after another, was most of a 1M-cell region's samples when the check read the record's
  // header).
  std::array<uint32_t, 512> published, others;
  std::array<T*, 512> published_cells, other_cells;
  std::array<float, 512> predicted;
  // Where each cell of a brick wholly in the box sits, from the brick's first cell.
  std::array<int64_t, 512> offset;
  for (uint32_t i = 0; i < 512; ++i) {
    offset[i] = static_cast<int64_t>((uint64_t{layout_->Z(i)} * ny + layout_->Y(i)) * nx + layout_->X(i));
  }
  static_assert(BrickImage::kNoHandle == kNone && BrickImage::kNeverChanged == kStaticHandle,
                "a brick's image is kept from the shard's handles");
  const BoxBricks box_bricks(box, bs);
  // The models of each brick's cells in one run, when they may be used: they hold each state at its
  // own order, without persistence.
  const std::shared_ptr<const BrickModels> brick_models =
      options.order >= 0 || (options.persistence && settings_.persistence) ? nullptr : RegionModels();
  std::array<T, 512> copied_values;
  walk.PrefetchImage(0);
  for (size_t b = 0; b < walk.bricks.size(); ++b) {
    walk.PrefetchImage(b + 1);
    const BoxWalk::BoxBrick& brick = walk.bricks[b];
    const BrickImage& image = *brick.image;
    if (held != nullptr) held[box_bricks.Index(brick.bx, brick.by, brick.bz)] = 1;
    // The brick's cells in the box, [lo, hi) in the brick's own coordinates.
    const BoxWalk::Cells c = walk.CellsIn(box, b);
    const std::array<uint32_t, 3> first = {brick.bx * bs[0], brick.by * bs[1], brick.bz * bs[2]};
    std::array<uint32_t, 3> lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = c.lo[a] - first[a];
      hi[a] = c.hi[a] - first[a];
    }
    // The never-changed and unobserved cells, a row at a time.
    const uint32_t row_cells = hi[0] - lo[0];
    T* plane = out + ((c.lo[2] - box.lo[2]) * ny + (c.lo[1] - box.lo[1])) * nx + (c.lo[0] - box.lo[0]);
    for (uint32_t z = lo[2]; z < hi[2]; ++z, plane += nx * ny) {
      T* row = plane;
      for (uint32_t y = lo[1], i = (z * bs[1] + y) * bs[0] + lo[0]; y < hi[1]; ++y, row += nx, i += bs[0]) {
        image.CopyRow(i, row_cells, row);
      }
    }
    // The dynamic ones: each brick's first cell is at `origin` in the box (before the box's start
    // when the brick begins outside it, so an index, not a pointer).
    const int64_t ox = int64_t{first[0]} - box.lo[0], oy = int64_t{first[1]} - box.lo[1],
                  oz = int64_t{first[2]} - box.lo[2];
    const int64_t origin = (oz * static_cast<int64_t>(ny) + oy) * static_cast<int64_t>(nx) + ox;
    // Into two lists, written after the loop: a store through T* inside it would make the compiler
    // reload the models' fields at each cell.
    size_t n = 0, m = 0;
    const auto gather = [&](uint32_t handle, T* at) ABSL_NO_THREAD_SAFETY_ANALYSIS {  // under the lock above
      if (models_.published(handle)) {
        __builtin_prefetch(models_.record(handle));  // for the kernel, after the brick's last
        published[n] = handle;
        published_cells[n++] = at;
      } else {
        others[m] = handle;
        other_cells[m++] = at;
      }
    };
    const bool whole = row_cells == bs[0] && hi[1] - lo[1] == bs[1] && hi[2] - lo[2] == bs[2];
    const auto in_box = [&](uint32_t cell) {
      const uint32_t x = layout_->X(cell), y = layout_->Y(cell), z = layout_->Z(cell);
      return x >= lo[0] && x < hi[0] && y >= lo[1] && y < hi[1] && z >= lo[2] && z < hi[2];
    };
    // The cells the brick's copied models cover: their models through the kernel as one run, the
    // values then scattered; the covered cells that had no model gathered as below.
    std::span<const BrickImage::DynamicCell> uncovered = image.dynamic();
    const size_t index = &image - images_.data();
    if (brick_models != nullptr && index < brick_models->size()) {
      const BrickModels::Brick& copied = brick_models->brick(index);
      if constexpr (std::is_same_v<T, uint8_t>) {
        model::PredictColumnsU8(brick_models->models(), copied.first, copied.count, copied.terms, table,
                                copied_values.data());
      } else {
        model::PredictColumns(brick_models->models(), copied.first, copied.count, copied.terms, table,
                              copied_values.data());
      }
      // (The count in a local: a store through T* = uint8_t* could change it, for all the compiler knows.)
      const uint16_t* cells = brick_models->cells() + copied.first;
      const uint32_t count = copied.count;
      if (whole) {
        T* const first_cell = out + origin;
        for (uint32_t i = 0; i < count; ++i) first_cell[offset[cells[i]]] = copied_values[i];
      } else {
        for (uint32_t i = 0; i < count; ++i) {
          if (in_box(cells[i])) out[origin + offset[cells[i]]] = copied_values[i];
        }
      }
      const BrickImage::DynamicCell* others = brick_models->others() + copied.others_first;
      for (uint32_t i = 0; i < copied.others_count; ++i) {
        if (whole || in_box(others[i].cell)) gather(others[i].handle, out + (origin + offset[others[i].cell]));
      }
      uncovered = uncovered.subspan(copied.covered);
    }
    if (whole) {
      T* const first_cell = out + origin;
      for (const BrickImage::DynamicCell& cell : uncovered) gather(cell.handle, first_cell + offset[cell.cell]);
    } else {
      for (const BrickImage::DynamicCell& cell : uncovered) {
        if (in_box(cell.cell)) gather(cell.handle, out + (origin + offset[cell.cell]));
      }
    }
    for (size_t i = 0; i < m; ++i) *other_cells[i] = CellValue<T>(PredictHandle(others[i], table, options));
    PredictPublished({published.data(), n}, table, options, predicted.data());
    if constexpr (std::is_same_v<T, uint8_t>) {
      // Quantised together (a vector loop), then scattered.
      std::array<uint8_t, 512> bytes;
      for (size_t i = 0; i < n; ++i) bytes[i] = CellValue<uint8_t>(predicted[i]);
      for (size_t i = 0; i < n; ++i) *published_cells[i] = bytes[i];
    } else {
      for (size_t i = 0; i < n; ++i) *published_cells[i] = predicted[i];
    }
  }
}
template void Shard::PredictBox(const CellBox&, const model::PhasorTable&, const PredictOptions&, float*,
                                uint8_t*) const;
template void Shard::PredictBox(const CellBox&, const model::PhasorTable&, const PredictOptions&, uint8_t*,
                                uint8_t*) const;

bool Shard::Observed(uint64_t key) const {
  base::ReaderMutexLock lock(&mutex_);
  const auto it = bricks_.find(BrickOf(key));
  return it != bricks_.end() && brick_data_[it->second].handles[key & 511] != kNone;
}

std::optional<std::pair<std::string, std::string>> Shard::Label(uint64_t key) const {
  base::ReaderMutexLock lock(&mutex_);
  const auto it = labels_.find(key);
  if (it == labels_.end()) return std::nullopt;
  return it->second;
}

std::optional<StateSnapshot> Shard::Snapshot(uint64_t key) const {
  base::ReaderMutexLock lock(&mutex_);
  const uint32_t slot = FindSlot(key);
  if (slot == kNone) return std::nullopt;
  StateSnapshot snapshot;
  const uint32_t d = slots_[slot].dynamic;
  snapshot.is_static = d == kNone;
  snapshot.static_state = slots_[slot].static_state;
  if (d != kNone) {
    snapshot.model = ModelOf(d);
    if (lossless_) snapshot.lossless = lossless_histories_[d];
  }
  if (auto it = labels_.find(key); it != labels_.end()) {
    snapshot.name = it->second.first;
    snapshot.group = it->second.second;
  }
  return snapshot;
}

ShardStats Shard::Stats() const {
  base::ReaderMutexLock lock(&mutex_);
  ShardStats stats;
  for (const Slot& slot : slots_) stats.states += slot.observed;
  stats.dynamic_states = slot_of_.size();
  stats.order_histogram.assign(settings_.max_order + 1, 0);
  for (size_t slot = 0; slot < slots_.size(); ++slot) {
    if (!slots_[slot].observed) continue;
    const uint32_t d = slots_[slot].dynamic;
    stats.observations += d == kNone ? slots_[slot].static_state.count() : spectra_.header(d).n;
  }
  for (uint32_t d = 0; d < slot_of_.size(); ++d) {
    const model::CompactModelHeader& h = models_.header(d);
    if (h.published) stats.order_histogram[h.order]++;
    const model::OrderErrors errors = errors_.Get(d);
    if (errors.weight() > 0) {
      stats.prediction_error_sum += errors.ErrorRate(h.order);
      stats.prediction_error_states++;
    }
  }
  for (const model::LosslessHistory& history : lossless_histories_) {
    const auto estimation = history.EstimationError();
    const auto prediction = history.PredictionError();
    stats.estimation_wrong += estimation.wrong;
    stats.estimation_observed += estimation.observed;
    stats.lossless_prediction_wrong += prediction.wrong;
    stats.lossless_prediction_observed += prediction.observed;
  }
  stats.wide_states = wide_.size();
  stats.memory_bytes = spectra_.bytes() + wide_.bytes() + models_.bytes() + errors_.bytes() +
                       persistence_.capacity() * sizeof(model::Persistence) +
                       slots_.capacity() * sizeof(Slot) +
                       brick_data_.capacity() * sizeof(Brick);
  for (const BrickImage& image : images_) stats.memory_bytes += image.memory_bytes();
  {
    base::MutexLock region_lock(&region_models_mutex_);
    if (region_models_ != nullptr) stats.memory_bytes += region_models_->memory_bytes();
  }
  if (auto used = env_->UsedBytes(); used.ok()) stats.disk_bytes = *used;
  return stats;
}

void Shard::ForEachKey(const std::function<void(uint64_t)>& f) const {
  base::ReaderMutexLock lock(&mutex_);
  for (const Slot& slot : slots_) {
    if (slot.observed) f(slot.key);
  }
}

void Shard::ForEachLabel(
    const std::function<void(uint64_t, const std::string&, const std::string&)>& f) const {
  base::ReaderMutexLock lock(&mutex_);
  for (const auto& [key, label] : labels_) f(key, label.first, label.second);
}

Shard::CheckpointImage Shard::PrepareCheckpoint(uint64_t lsn, const DedupTable& dedup) {
  CheckpointImage image;
  image.lsn = lsn;
  {
    base::ReaderMutexLock lock(&mutex_);  // the writer is the caller: only readers run alongside
    std::vector<uint32_t> dirty = dirty_slots_;
    std::sort(dirty.begin(), dirty.end(),
              [&](uint32_t a, uint32_t b) ABSL_SHARED_LOCKS_REQUIRED(mutex_) { return slots_[a].key < slots_[b].key; });
    std::vector<uint64_t> dirty_bricks;  // a published model alone changes no brick
    for (uint32_t slot : dirty) {
      if (!(slots_[slot].dirty & kDirtyAll)) continue;
      const uint64_t brick = BrickOf(slots_[slot].key);
      if (dirty_bricks.empty() || dirty_bricks.back() != brick) dirty_bricks.push_back(brick);
    }
    for (uint32_t slot : dirty) {
      const uint32_t d = slots_[slot].dynamic;
      if (d == kNone) continue;
      const uint64_t key = slots_[slot].key;
      // A state is published from its first publication on, so a published record is never
      // deleted: the one written last is the state's.
      if (models_.published(d)) image.published.emplace_back(key, model::EncodePublishedModel(PublishedOf(d)));
      if (!(slots_[slot].dirty & kDirtyAll)) continue;
      image.dynamic.emplace_back(key, model::EncodeStateModel(UnpublishedModelOf(d)));
      if (lossless_) image.lossless.emplace_back(key, lossless_histories_[d].Encode());
      if (wide_.wide(d)) image.wide.emplace_back(key, wide_.Encode(d));
    }
    // A brick's never-changed states are written together; a brick left with none is deleted
    // (an empty value).
    for (uint64_t brick : dirty_bricks) {
      const Brick& data = brick_data_[bricks_.at(brick)];
      StaticBrick value;
      for (uint32_t i = 0; i < 512; ++i) {
        const uint32_t slot = SlotAt(data, i);
        if (slot != kNone && slots_[slot].dynamic == kNone) value.Add(i, slots_[slot].static_state);
      }
      image.statics.emplace_back(brick, value.empty() ? std::string() : value.Encode());
    }
    for (uint64_t key : dirty_labels_) {
      const auto& [name, group] = labels_.at(key);
      image.labels.emplace_back(key, shard_records::EncodeLabel(name, group));
    }
    image.touched = EncodeTouched();
    image.dedup = dedup.Encode();
  }
  base::WriterMutexLock exclusive(&mutex_);
  for (uint32_t slot : dirty_slots_) slots_[slot].dirty = 0;
  dirty_slots_.clear();
  dirty_labels_.clear();
  checkpoint_lsn_ = lsn;
  checkpoint_dedup_ = dedup;
  return image;
}

absl::Status Shard::WriteCheckpoint(const CheckpointImage& image) {
  base::MutexLock lock(&checkpoint_write_mutex_);
  // The states of a failed image are clean in memory but not on disk: a later image must not
  // move the checkpoint past them.
  if (!checkpoint_write_error_.ok()) return checkpoint_write_error_;
  const absl::Status written = env_->Write([&](LmdbTxn& txn) -> absl::Status {
    auto static_db = txn.Db(kStaticDb);
    auto dynamic_db = txn.Db(kDynamicDb);
    auto published_db = txn.Db(kPublishedDb);
    auto lossless_db = txn.Db(kLosslessDb);
    auto wide_db = txn.Db(kWideDb);
    auto labels_db = txn.Db(kLabelsDb);
    auto meta_db = txn.Db(kMetaDb);
    for (auto* db : {&static_db, &dynamic_db, &published_db, &lossless_db, &wide_db, &labels_db, &meta_db}) {
      if (!db->ok()) return db->status();
    }
    const auto put_all = [&](MDB_dbi db, const std::vector<std::pair<uint64_t, std::string>>& records) {
      for (const auto& [key, value] : records) {
        if (absl::Status s = txn.Put(db, KeyBytes(key), Bytes(value)); !s.ok()) return s;
      }
      return absl::OkStatus();
    };
    if (absl::Status s = put_all(*dynamic_db, image.dynamic); !s.ok()) return s;
    if (absl::Status s = put_all(*published_db, image.published); !s.ok()) return s;
    if (absl::Status s = put_all(*lossless_db, image.lossless); !s.ok()) return s;
    if (absl::Status s = put_all(*wide_db, image.wide); !s.ok()) return s;
    for (const auto& [brick, value] : image.statics) {
      const auto key = KeyBytes(brick);
      absl::Status s = value.empty() ? txn.Delete(*static_db, key) : txn.Put(*static_db, key, Bytes(value));
      if (!s.ok()) return s;
    }
    if (absl::Status s = put_all(*labels_db, image.labels); !s.ok()) return s;
    uint8_t lsn_bytes[8];
    std::memcpy(lsn_bytes, &image.lsn, 8);
    if (absl::Status s = txn.Put(*meta_db, Bytes(kLsnKey), lsn_bytes); !s.ok()) return s;
    if (absl::Status s = txn.Put(*meta_db, Bytes(kTouchedKey), Bytes(image.touched)); !s.ok()) return s;
    return txn.Put(*meta_db, Bytes(kDedupKey), Bytes(image.dedup));
  });
  if (!written.ok()) checkpoint_write_error_ = written;
  return written;
}

absl::Status Shard::Load() {
  return env_->Read([&](LmdbTxn& txn) ABSL_NO_THREAD_SAFETY_ANALYSIS -> absl::Status {
    auto meta_db = txn.Db(kMetaDb);
    if (absl::IsNotFound(meta_db.status())) return absl::OkStatus();  // a new shard
    if (!meta_db.ok()) return meta_db.status();
    // An absent meta record is a shard never checkpointed; a damaged one (DataLoss) is an error.
    if (auto lsn = txn.Get(*meta_db, Bytes(kLsnKey)); lsn.ok()) {
      auto decoded = shard_records::DecodeCheckpointLsn(*lsn);
      if (!decoded.ok()) return decoded.status();
      checkpoint_lsn_ = *decoded;
    } else if (!absl::IsNotFound(lsn.status())) {
      return lsn.status();
    }
    if (auto dedup = txn.Get(*meta_db, Bytes(kDedupKey)); dedup.ok()) {
      auto table = DedupTable::Decode(View(*dedup));
      if (!table.ok()) return table.status();
      checkpoint_dedup_ = *std::move(table);
    } else if (!absl::IsNotFound(dedup.status())) {
      return dedup.status();
    }
    // Read now, applied once the dynamic states are loaded (a store without it: all touched).
    std::optional<std::string> touched;
    if (auto t = txn.Get(*meta_db, Bytes(kTouchedKey)); t.ok()) {
      touched = std::string(View(*t));
    } else if (!absl::IsNotFound(t.status())) {
      return t.status();
    }
    absl::Status failure;
    const auto scan = [&](const char* family, const std::function<absl::Status(uint64_t, std::string_view)>& f) {
      auto db = txn.Db(family);
      if (absl::IsNotFound(db.status())) return absl::OkStatus();
      if (!db.ok()) return db.status();
      absl::Status scanned = txn.Scan(*db, {}, {}, [&](auto key, auto value) {
        if (key.size() != 8) {
          failure = absl::DataLossError(absl::StrCat(family, ": a key is ", key.size(), " bytes, not 8"));
          return false;
        }
        const uint64_t k = KeyFromBytes(key.data());
        if (absl::Status s = f(k, View(value)); !s.ok()) {
          failure = WithKey(s, family, k);
          return false;
        }
        return true;
      });
      return scanned.ok() ? failure : scanned;
    };
    // The lambdas below are not analysed either (see Load).
    if (absl::Status s = scan(kStaticDb, [&](uint64_t brick, std::string_view value) ABSL_NO_THREAD_SAFETY_ANALYSIS
                                  -> absl::Status {
          auto decoded = StaticBrick::Decode(value);
          if (!decoded.ok()) return decoded.status();
          decoded->ForEach([&](uint32_t i, const model::StaticState& state) ABSL_NO_THREAD_SAFETY_ANALYSIS {
            const uint64_t key = brick << kBrickBits | i;
            slots_[FindOrAddSlot(key)].static_state = state;
            SetHandle(key, kStaticHandle | static_cast<uint32_t>(state.value()));
          });
          return absl::OkStatus();
        });
        !s.ok()) {
      return s;
    }
    if (absl::Status s = scan(kDynamicDb, [&](uint64_t key, std::string_view value) ABSL_NO_THREAD_SAFETY_ANALYSIS
                                  -> absl::Status {
          auto decoded = model::DecodeStateModel<float>(value, settings_);
          if (!decoded.ok()) return decoded.status();
          const uint32_t slot = FindOrAddSlot(key);
          StoreModel(slots_[slot].dynamic == kNone ? AddDynamic(slot) : slots_[slot].dynamic, *decoded);
          return absl::OkStatus();
        });
        !s.ok()) {
      return s;
    }
    // After the dynamic records: a published record replaces the model a dynamic record written
    // before format 3 holds.
    if (absl::Status s = scan(kPublishedDb, [&](uint64_t key, std::string_view value) ABSL_NO_THREAD_SAFETY_ANALYSIS
                                  -> absl::Status {
          const uint32_t slot = FindSlot(key);
          if (slot == kNone || slots_[slot].dynamic == kNone) {
            return absl::DataLossError("a published model without its state");
          }
          auto decoded = model::DecodePublishedModel(value, settings_.periods.size(), settings_.max_order);
          if (!decoded.ok()) return decoded.status();
          BeforeModelChange(slots_[slot].dynamic);
          models_.Set(slots_[slot].dynamic, *decoded);
          return absl::OkStatus();
        });
        !s.ok()) {
      return s;
    }
    if (absl::Status s = scan(kLosslessDb, [&](uint64_t key, std::string_view value) ABSL_NO_THREAD_SAFETY_ANALYSIS
                                  -> absl::Status {
          auto decoded = model::LosslessHistory::Decode(value);
          if (!decoded.ok()) return decoded.status();
          const uint32_t slot = FindSlot(key);
          if (!lossless_ || slot == kNone || slots_[slot].dynamic == kNone) {
            return absl::DataLossError("a lossless history without its state");
          }
          lossless_histories_[slots_[slot].dynamic] = *std::move(decoded);
          return absl::OkStatus();
        });
        !s.ok()) {
      return s;
    }
    // After the float records: a wide state's exact double body replaces the one widened from them.
    if (absl::Status s = scan(kWideDb, [&](uint64_t key, std::string_view value) ABSL_NO_THREAD_SAFETY_ANALYSIS
                                  -> absl::Status {
          const uint32_t slot = FindSlot(key);
          if (slot == kNone || slots_[slot].dynamic == kNone) return absl::DataLossError("a wide body without its state");
          return wide_.Decode(slots_[slot].dynamic, value);
        });
        !s.ok()) {
      return s;
    }
    if (touched) {
      if (absl::Status s = DecodeTouched(*touched); !s.ok()) return s;
    }
    return scan(kLabelsDb, [&](uint64_t key, std::string_view value) ABSL_NO_THREAD_SAFETY_ANALYSIS -> absl::Status {
      auto label = shard_records::DecodeLabel(value);
      if (!label.ok()) return label.status();
      labels_[key] = *std::move(label);
      return absl::OkStatus();
    });
  });
}

}  // namespace fremen::storage
