#include "storage/map_store_impl.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <future>
#include <type_traits>

#include "absl/strings/cord.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "absl/strings/ascii.h"
#include "absl/time/clock.h"
#include "storage/brick_region.h"
#include "storage/cell_key.h"
#include "storage/parallel_shards.h"

namespace fremen::storage {

namespace {

// The first byte of a log record: what it holds.
constexpr char kBatchRecord = 'B';    // an ObservationBatch follows
constexpr char kPublishRecord = 'P';  // every shard republished its models here

// Marks Submit's refusal for a full queue (IsQueueFull).
constexpr char kQueueFullPayload[] = "type.fremen/storage.QueueFull";

// A group with fewer observations is applied on the applier's thread, shard after shard: waking a
// shard's worker and waiting for it (a futex wake and two context switches) costs more than
// applying a few thousand observations. Small scans (1000 cells, groups of ~7 batches): context
// switches per batch 2.2 -> 1.7 (docs/performance.md, "Small scans").
constexpr uint64_t kParallelApplyObservations = 8192;

std::string ShardDir(const std::string& dir, uint32_t i) { return absl::StrCat(dir, "/shard-", i); }
std::string LastUpdatePath(const std::string& dir) { return dir + "/last_update"; }
std::string MovedToPath(const std::string& dir) { return dir + "/moved_to"; }
// An incoming copy's marker (MoveState::kIncoming): the snapshot's LSN, in decimal.
std::string IncomingPath(const std::string& dir) { return dir + "/" + kIncomingFile; }

absl::Status MakeDir(const std::string& dir) {
  if (mkdir(dir.c_str(), 0750) != 0 && errno != EEXIST) {
    return absl::InternalError(absl::StrCat("cannot create ", dir, ": ", std::strerror(errno)));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status MovingError(const std::string& map) {
  return absl::UnavailableError(absl::StrCat("map ", map, " is moving to another daemon; retry"));
}

bool IsQueueFull(const absl::Status& status) {
  return status.code() == absl::StatusCode::kResourceExhausted && status.GetPayload(kQueueFullPayload).has_value();
}

namespace {

// The observer of a store without one.
class IgnoringObserver final : public MapObserver {
 public:
  void BatchAnswered(const BatchAck&) override {}
  void LogSynced(uint64_t, absl::Duration) override {}
  void Checkpointed(uint64_t, absl::Duration) override {}
  void Recovered(absl::Duration) override {}
};

std::shared_ptr<MapObserver> ObserverOf(const StoreOptions& options, const std::string& map) {
  std::shared_ptr<MapObserver> observer = options.observer == nullptr ? nullptr : options.observer->ForMap(map);
  return observer != nullptr ? observer : std::make_shared<IgnoringObserver>();
}

// The bytes of the records a checkpoint writes.
uint64_t ImageBytes(const Shard::CheckpointImage& image) {
  uint64_t bytes = image.touched.size() + image.dedup.size();
  for (const auto* records : {&image.dynamic, &image.published, &image.lossless, &image.wide, &image.labels, &image.statics}) {
    for (const auto& [key, record] : *records) bytes += sizeof(key) + record.size();
  }
  return bytes;
}

}  // namespace

MapStoreImpl::MapStoreImpl(MapInfo info, std::string dir, StoreOptions options, std::unique_ptr<model::ModelSettings> settings)
    : info_(std::move(info)),
      dir_(std::move(dir)),
      options_(options),
      observer_(ObserverOf(options_, info_.name)),
      settings_(std::move(settings)) {}

absl::StatusOr<std::unique_ptr<MapStore>> MapStore::Open(const MapInfo& info, const std::string& dir,
                                                         const StoreOptions& options) {
  auto store = MapStoreImpl::Open(info, dir, options);
  if (!store.ok()) return store.status();
  return std::unique_ptr<MapStore>(*std::move(store));
}

absl::StatusOr<std::unique_ptr<MapStoreImpl>> MapStoreImpl::Open(const MapInfo& info, const std::string& dir,
                                                                 const StoreOptions& options) {
  if (absl::Status valid = ValidateMapInfo(info); !valid.ok()) return valid;
  if (info.shards == 0) return absl::InvalidArgumentError("shards must be set before a map is opened");
  auto settings = ModelSettingsOf(info);
  if (!settings.ok()) return settings.status();
  if (absl::Status s = MakeDir(dir); !s.ok()) return s;
  auto store = std::unique_ptr<MapStoreImpl>(
      new MapStoreImpl(info, dir, options, std::make_unique<model::ModelSettings>(*std::move(settings))));
  LmdbOptions lmdb;
  lmdb.initial_map_size = options.initial_map_size;
  for (uint32_t i = 0; i < info.shards; ++i) {
    auto shard = Shard::Open(store->info_, *store->settings_, ShardDir(dir, i), lmdb, options.widen_records_at);
    if (!shard.ok()) {
      return absl::Status(shard.status().code(), absl::StrCat("map ", info.name, " shard ", i, ": ",
                                                              shard.status().message()));
    }
    store->shards_.push_back(*std::move(shard));
  }
  // Started before recovery, which applies the log's batches on them.
  store->workers_ = std::make_unique<ShardWorkers>(info.shards, "fremen-shard");
  const absl::Time recovery_start = absl::Now();
  if (absl::Status s = store->Recover(); !s.ok()) {
    return absl::Status(s.code(), absl::StrCat("map ", info.name, ": recovery: ", s.message()));
  }
  store->observer_->Recovered(absl::Now() - recovery_start);
  // Only a report: an unreadable record is shown as none rather than keeping the map closed.
  if (auto last = ReadUpdateRecord(options.env, LastUpdatePath(dir)); last.ok()) store->last_update_ = *std::move(last);
  // A committed move stays committed: this copy must not take writes the new owner will not see.
  if (auto to = options.env->ReadFile(MovedToPath(dir)); to.ok()) {
    base::MutexLock lock(&store->queue_mutex_);
    store->move_ = MoveStatus{MoveState::kMoved, *std::move(to)};
  } else if (!absl::IsNotFound(to.status())) {
    return to.status();
  }
  // A move's copy waiting for its tail stays so: it must not take writes before the batches the
  // source acknowledged after its snapshot.
  if (auto incoming = options.env->ReadFile(IncomingPath(dir)); incoming.ok()) {
    uint64_t lsn = 0;
    if (!absl::SimpleAtoi(absl::StripAsciiWhitespace(*incoming), &lsn)) {
      return absl::DataLossError(absl::StrCat("map ", info.name, ": ", IncomingPath(dir), " does not hold an LSN"));
    }
    base::MutexLock lock(&store->queue_mutex_);
    store->move_ = MoveStatus{MoveState::kIncoming, "", lsn};
  } else if (!absl::IsNotFound(incoming.status())) {
    return incoming.status();
  }
  store->committer_ = std::thread([s = store.get()] { s->CommitLoop(); });
  store->applier_ = std::thread([s = store.get()] { s->ApplyLoop(); });
  return store;
}

MapStoreImpl::~MapStoreImpl() { (void)Close(); }

void MapStoreImpl::Warn(const std::string& message) const {
  if (options_.log_warning) {
    options_.log_warning(message);
  } else {
    std::fprintf(stderr, "fremen storage: warning: %s\n", message.c_str());
  }
}

absl::Status MapStoreImpl::Recover() {
  // Replay starts after the oldest checkpoint; new records start above the newest (the LSN floor).
  uint64_t from = UINT64_MAX, newest = 0;
  for (const auto& shard : shards_) {
    from = std::min(from, shard->checkpoint_lsn());
    newest = std::max(newest, shard->checkpoint_lsn());
    written_lsn_ = from;
    dedup_.MergeFrom(shard->checkpoint_dedup());
  }
  // Replayed batches are applied in groups, every shard's part on the shard's own thread (as the
  // committer applies a group), while decoding stays on this thread: a shard that checkpointed
  // past a record skips it, and a publication's record ends its group, so that every shard folds in
  // its batches and publications in log order.
  struct Replayed {
    uint64_t lsn;
    Pending pending;
  };
  std::vector<Replayed> group;
  uint64_t group_observations = 0;
  const auto apply_group = [&]() ABSL_NO_THREAD_SAFETY_ANALYSIS {  // see Recover
    if (group.empty()) return;
    std::vector<ScanContext> scans;
    scans.reserve(group.size());
    for (const Replayed& r : group) scans.emplace_back(settings_->periods, r.pending.batch.time);
    workers_->RunOnAll([&](uint32_t s) ABSL_NO_THREAD_SAFETY_ANALYSIS {
      for (size_t i = 0; i < group.size(); ++i) {
        if (shards_[s]->checkpoint_lsn() >= group[i].lsn) continue;  // the checkpoint has it already
        ApplyToShard(s, group[i].pending, scans[i]);
        shards_[s]->ApplyLabels(group[i].pending.labels[s]);
      }
    });
    group.clear();
    group_observations = 0;
  };
  // A group's decoded batches stay in memory until it is applied: a few tens of MB.
  constexpr uint64_t kGroupObservations = uint64_t{1} << 21;
  constexpr size_t kGroupRecords = 512;
  auto replayed = ReplayWal(dir_ + "/wal", from, [&](uint64_t lsn, std::span<const uint8_t> payload)
                                                     ABSL_NO_THREAD_SAFETY_ANALYSIS -> absl::Status {  // see Recover
    if (payload.size() == 1 && payload[0] == kPublishRecord) {
      apply_group();
      for (const auto& shard : shards_) {
        if (shard->checkpoint_lsn() < lsn) shard->PublishAll();
      }
      return absl::OkStatus();
    }
    if (payload.empty() || payload[0] != kBatchRecord) {
      return absl::DataLossError(absl::StrCat("log record ", lsn, ": unknown record kind"));
    }
    auto batch = DecodeBatch({reinterpret_cast<const char*>(payload.data()) + 1, payload.size() - 1});
    if (!batch.ok()) return absl::DataLossError(absl::StrCat("log record ", lsn, ": ", batch.status().message()));
    if (absl::Status expanded = ExpandCompact(info_, *batch); !expanded.ok()) {
      return absl::DataLossError(absl::StrCat("log record ", lsn, ": ", expanded.message()));
    }
    dedup_.Record(batch->writer_id, batch->sequence,
                  BatchFingerprint({reinterpret_cast<const char*>(payload.data()) + 1, payload.size() - 1}));
    Pending pending{*std::move(batch), nullptr, {}, {}, {}, {}, {}, {}, {}, {}};
    pending.ack = Classify(info_, pending.batch, pending.accept);
    SplitByShard(pending);
    group_observations += pending.batch.observation_count();
    group.push_back({lsn, std::move(pending)});
    if (group_observations >= kGroupObservations || group.size() >= kGroupRecords) apply_group();
    return absl::OkStatus();
  }, options_.env);
  if (replayed.ok()) apply_group();
  if (!replayed.ok()) return replayed.status();
  // A checkpoint is only written once its records are durable, and the log is dropped only once
  // every shard has it: a shard behind the newest checkpoint whose log stops short of it lacks
  // records that existed.
  if (replayed->last_lsn < newest && from < newest) {
    return absl::DataLossError(absl::StrCat("the write-ahead log ends at LSN ", replayed->last_lsn,
                                            " but a shard checkpointed up to LSN ", newest, " while another stopped at ",
                                            from, ": records ", std::max(from, replayed->last_lsn) + 1, "..", newest,
                                            " are lost for it"));
  }
  WalOptions wal_options;
  wal_options.segment_bytes = options_.log_segment_bytes;
  wal_options.env = options_.env;
  wal_options.min_next_lsn = newest + 1;
  wal_options.replayed = &*replayed;
  auto wal = WalWriter::Open(dir_ + "/wal", wal_options);
  if (!wal.ok()) return wal.status();
  wal_ = *std::move(wal);
  if (replayed->truncated_tail) {
    Warn(absl::StrCat("map ", info_.name, ": write-ahead log ", replayed->torn_tail_file, ": cut a torn tail of ",
                      replayed->torn_tail_bytes, " bytes at byte ", replayed->torn_tail_offset,
                      " (a write a crash interrupted: never acknowledged)"));
  }
  applied_dedup_ = dedup_;
  applied_lsn_ = wal_->last_lsn();
  for (const auto& shard : shards_) {
    shard->ForEachLabel([&](uint64_t key, const std::string&, const std::string& group) ABSL_NO_THREAD_SAFETY_ANALYSIS {
      if (!group.empty()) groups_[group].push_back(key);
    });
  }
  return absl::OkStatus();
}

MapStoreImpl::Pending MapStoreImpl::Prepare(ObservationBatch batch, AckCallback done) const {
  Pending pending{std::move(batch), std::move(done), {}, {}, {}, {}, {}, {}, {}, {}};
  pending.ack = Classify(info_, pending.batch, pending.accept);
  pending.record.push_back(kBatchRecord);
  pending.record += EncodeBatch(pending.batch);
  pending.fingerprint = BatchFingerprint(std::string_view(pending.record).substr(1));
  SplitByShard(pending);
  return pending;
}

void MapStoreImpl::SplitByShard(Pending& pending) const {
  std::vector<std::vector<uint64_t>>& keys = pending.keys;
  std::vector<std::vector<float>>& values = pending.values;
  keys.assign(info_.shards, {});
  values.assign(info_.shards, {});
  pending.labels.assign(info_.shards, {});
  const ObservationBatch& b = pending.batch;
  for (const StateLabel& l : b.labels) pending.labels[ShardOf(l.key, info_.shards)].push_back(l);
  // Bricks spread evenly over the shards: room for a fair share and some, so that a shard's arrays
  // rarely grow while they fill.
  const size_t share = b.observation_count() / info_.shards + b.observation_count() / 8 + 16;
  for (uint32_t s = 0; s < info_.shards; ++s) {
    keys[s].reserve(share);
    values[s].reserve(share);
  }
  // A coherent scan's neighbouring keys share their brick, so its shard (a hash and a division) is
  // computed once per run of the brick's keys; a scan's run goes to its shard in one copy when all
  // of it is accepted.
  if (!b.is_history()) {
    const size_t n = b.keys.size();
    const bool all_accepted = pending.ack.rejected == 0;  // Classify's count: no run needs its accept bytes read
    const uint64_t* const in = b.keys.data();
    for (size_t i = 0; i < n;) {
      const uint64_t first = in[i];
      size_t end = i + 1;
      // Four keys a test while the run lasts (a flat brick's row is 32): keys of one brick share
      // every bit above a brick's.
      for (; end + 4 <= n; end += 4) {
        const uint64_t differ = (in[end] ^ first) | (in[end + 1] ^ first) | (in[end + 2] ^ first) | (in[end + 3] ^ first);
        if (BrickOf(differ) != 0) break;
      }
      while (end < n && BrickOf(in[end]) == BrickOf(first)) ++end;
      const uint32_t s = ShardOf(b.keys[i], info_.shards);
      if (all_accepted || std::memchr(&pending.accept[i], 0, end - i) == nullptr) {
        keys[s].insert(keys[s].end(), b.keys.begin() + static_cast<ptrdiff_t>(i), b.keys.begin() + static_cast<ptrdiff_t>(end));
        values[s].insert(values[s].end(), b.values.begin() + static_cast<ptrdiff_t>(i),
                         b.values.begin() + static_cast<ptrdiff_t>(end));
      } else {
        for (size_t k = i; k < end; ++k) {
          if (!pending.accept[k]) continue;
          keys[s].push_back(b.keys[k]);
          values[s].push_back(b.values[k]);
        }
      }
      i = end;
    }
  }
  uint64_t brick = ~uint64_t{0};
  uint32_t shard = 0;
  // A history's runs: the batch's observations split where the time changes (rejected ones
  // included, as in the scans the history stands for), each shard's part of a run one run of it.
  std::vector<uint64_t> last_run;  // by shard, the batch run its last run is part of, +1
  uint64_t run = 0;
  if (b.is_history()) {
    pending.runs.assign(info_.shards, {});
    last_run.assign(info_.shards, 0);
  }
  for (size_t i = 0; b.is_history() && i < b.keys.size(); ++i) {
    if (i > 0 && b.times[i] != b.times[i - 1]) ++run;
    if (!pending.accept[i]) continue;
    if (BrickOf(b.keys[i]) != brick) {
      brick = BrickOf(b.keys[i]);
      shard = ShardOf(b.keys[i], info_.shards);
    }
    const uint32_t s = shard;
    const uint32_t end = static_cast<uint32_t>(keys[s].size()) + 1;
    if (last_run[s] == run + 1) {
      pending.runs[s].back().end = end;
    } else {
      pending.runs[s].push_back({b.times[i], end});
      last_run[s] = run + 1;
    }
    keys[s].push_back(b.keys[i]);
    values[s].push_back(b.values[i]);
  }
  const DensePatch& p = b.patch;
  const GridKeys grid_keys = info_.grid.keys();
  size_t j = b.keys.size();
  for (uint32_t z = 0; z < p.size[2]; ++z) {
    for (uint32_t y = 0; y < p.size[1]; ++y) {
      for (uint32_t x = 0; x < p.size[0]; ++x, ++j) {
        if (!pending.accept[j]) continue;
        const uint64_t key = grid_keys.Key(p.origin[0] + x, p.origin[1] + y, p.origin[2] + z);
        const uint32_t s = ShardOf(key, info_.shards);
        keys[s].push_back(key);
        values[s].push_back(p.values[j - b.keys.size()]);
      }
    }
  }
}

absl::Status MapStoreImpl::Enqueue(ObservationBatch batch, AckCallback done, bool tail) {
  if (absl::Status valid = ValidateBatch(info_, batch); !valid.ok()) return valid;
  if (info_.lossless_sampling_period > 0 && batch.time < info_.lossless_origin && !batch.is_history()) {
    return absl::InvalidArgumentError(absl::StrCat("time must not be before the map's lossless origin ",
                                                   info_.lossless_origin, ", got ", batch.time));
  }
  if (info_.lossless_sampling_period > 0) {
    for (size_t i = 0; i < batch.times.size(); ++i) {
      if (batch.times[i] < info_.lossless_origin) {
        return absl::InvalidArgumentError(absl::StrCat("times[", i, "] must not be before the map's lossless origin ",
                                                       info_.lossless_origin, ", got ", batch.times[i]));
      }
    }
  }
  const uint64_t n = batch.observation_count();
  const auto refusal = [&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(queue_mutex_) -> absl::Status {
    if (closing_) return absl::UnavailableError(absl::StrCat("map ", info_.name, " is closing"));
    if (!write_error_.ok()) return write_error_;
    if (tail ? move_.state != MoveState::kIncoming : !TakesWrites(move_.state)) return MovingError(info_.name);
    if (!tail && !FitsLocked(n)) {
      absl::Status full = absl::ResourceExhaustedError(
          absl::StrCat("map ", info_.name, " is behind on ingest: too many queued observations; retry"));
      full.SetPayload(kQueueFullPayload, absl::Cord());
      return full;
    }
    return absl::OkStatus();
  };
  {
    // Checked before the batch is prepared, so that a refusal costs nothing; again after, since
    // the queue may have filled meanwhile.
    base::MutexLock lock(&queue_mutex_);
    if (absl::Status refused = refusal(); !refused.ok()) return refused;
  }
  Pending pending = Prepare(std::move(batch), std::move(done));
  {
    base::MutexLock lock(&queue_mutex_);
    if (absl::Status refused = refusal(); !refused.ok()) return refused;
    queued_observations_ += n;
    queue_.push_back(std::move(pending));
  }
  queue_ready_.Signal();
  return absl::OkStatus();
}

void MapStoreImpl::OnRoom(uint64_t observations, std::function<void()> f) {
  {
    base::MutexLock lock(&queue_mutex_);
    if (!FitsLocked(observations) && !closing_ && write_error_.ok() && TakesWrites(move_.state)) {
      room_waiters_.push_back(std::move(f));
      return;
    }
  }
  f();
}

absl::StatusOr<BatchAck> MapStoreImpl::Write(ObservationBatch batch) {
  std::promise<absl::StatusOr<BatchAck>> promise;
  auto future = promise.get_future();
  if (absl::Status s = Submit(std::move(batch), [&](absl::StatusOr<BatchAck> ack) { promise.set_value(std::move(ack)); });
      !s.ok()) {
    return s;
  }
  absl::StatusOr<BatchAck> ack = future.get();
  if (ack.ok() && !ack->error.ok()) return ack->error;
  return ack;
}

uint64_t MapStoreImpl::LastSequence(uint64_t writer) const {
  base::MutexLock lock(&dedup_mutex_);
  return dedup_.LastSequence(writer);
}

absl::StatusOr<uint64_t> MapStoreImpl::RunControl(Control::Kind kind, std::function<void(uint64_t, uint64_t)> progress) {
  std::promise<absl::StatusOr<uint64_t>> promise;
  auto future = promise.get_future();
  {
    base::MutexLock lock(&queue_mutex_);
    if (!committer_.joinable() || closing_) return absl::UnavailableError(absl::StrCat("map ", info_.name, " is closed"));
    controls_.push_back(
        {kind, [&](absl::StatusOr<uint64_t> r) { promise.set_value(std::move(r)); }, std::move(progress)});
  }
  queue_ready_.Signal();
  return future.get();
}

absl::Status MapStoreImpl::Checkpoint() { return RunControl(Control::Kind::kCheckpoint).status(); }

absl::StatusOr<uint64_t> MapStoreImpl::PublishModels(std::function<void(uint64_t, uint64_t)> progress) {
  {
    base::MutexLock lock(&queue_mutex_);
    if (move_.state != MoveState::kServing) return MovingError(info_.name);
  }
  return RunControl(Control::Kind::kPublish, std::move(progress));
}

absl::Status MapStoreImpl::RecordUpdate(const UpdateRecord& record) {
  base::MutexLock lock(&last_update_mutex_);
  if (absl::Status s = WriteUpdateRecord(options_.env, LastUpdatePath(dir_), record); !s.ok()) return s;
  last_update_ = record;
  return absl::OkStatus();
}

absl::Status MapStoreImpl::Close() {
  {
    base::MutexLock lock(&queue_mutex_);
    closing_ = true;
  }
  queue_ready_.Signal();
  if (committer_.joinable()) committer_.join();
  if (applier_.joinable()) applier_.join();
  WaitCheckpointWrite();  // the applier waits for it before it ends; the applier is gone now
  base::MutexLock lock(&queue_mutex_);
  return write_error_;
}

absl::Status MapStoreImpl::WriteError() const {
  base::MutexLock lock(&queue_mutex_);
  return write_error_;
}

absl::Status MapStoreImpl::StopWrites() {
  std::vector<std::function<void()>> room;
  {
    base::MutexLock lock(&queue_mutex_);
    if (move_.state == MoveState::kIncoming) {
      return absl::FailedPreconditionError(absl::StrCat("map ", info_.name, " is a move's copy waiting for its tail"));
    }
    if (TakesWrites(move_.state)) move_.state = MoveState::kWritesStopped;
    room.swap(room_waiters_);
  }
  // As after a latched error: waiters resubmit and learn that the map is moving.
  for (auto& f : room) f();
  // Queued before the refusal: the checkpoint runs after them, so they are applied and answered.
  return Checkpoint();
}

absl::Status MapStoreImpl::ResumeWrites() {
  base::MutexLock lock(&queue_mutex_);
  if (move_.state == MoveState::kMoved) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info_.name, " has moved to ", move_.moved_to, "; delete this copy instead"));
  }
  if (move_.state == MoveState::kIncoming) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info_.name, " is a move's copy waiting for its tail; delete it instead"));
  }
  move_.state = MoveState::kServing;
  base::MutexLock tail(&tail_mutex_);
  tail_.reset();
  return absl::OkStatus();
}

absl::Status MapStoreImpl::MarkMoved(const std::string& to) {
  base::MutexLock lock(&queue_mutex_);
  if (move_.state == MoveState::kMoved) return absl::OkStatus();
  if (move_.state != MoveState::kWritesStopped) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info_.name, " takes writes: stop them before the move is committed"));
  }
  if (absl::Status s = WriteFileAtomically(options_.env, MovedToPath(dir_), to); !s.ok()) return s;
  move_ = MoveStatus{MoveState::kMoved, to};
  base::MutexLock tail(&tail_mutex_);
  tail_.reset();
  return absl::OkStatus();
}

MoveStatus MapStoreImpl::Move() const {
  base::MutexLock lock(&queue_mutex_);
  return move_;
}

absl::Status MapStoreImpl::StartTail() {
  base::MutexLock lock(&queue_mutex_);
  if (!TakesWrites(move_.state)) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info_.name, " does not take writes here (a move is under way or done): no copy starts"));
  }
  // Set under queue_mutex_, so that a PublishModels that saw the map serving has queued its
  // request before this; its record then comes before the snapshot's checkpoint.
  move_.state = MoveState::kCopying;
  base::MutexLock tail(&tail_mutex_);
  tail_ = TailCapture{};  // not emplace(): clang finds a nested struct with member initialisers not default-constructible here
  return absl::OkStatus();
}

void MapStoreImpl::CaptureTail(uint64_t lsn, const std::string& record) {
  base::MutexLock lock(&tail_mutex_);
  if (!tail_ || !tail_->given_up.empty()) return;
  tail_->bytes += record.size();
  if (tail_->bytes > options_.max_tail_bytes) {
    tail_->given_up = absl::StrCat("more than ", options_.max_tail_bytes, " bytes were written during the copy");
    tail_->records.clear();
    return;
  }
  // The record without its kind byte: the batch's EncodeBatch bytes.
  tail_->records.push_back(TailRecord{lsn, record.substr(1)});
}

void MapStoreImpl::GiveUpTail(const std::string& why) {
  base::MutexLock lock(&tail_mutex_);
  if (!tail_ || !tail_->given_up.empty()) return;
  tail_->given_up = why;
  tail_->records.clear();
}

absl::StatusOr<std::vector<TailRecord>> MapStoreImpl::Tail(uint64_t after) const {
  {
    base::MutexLock lock(&queue_mutex_);
    if (!write_error_.ok()) return write_error_;
    if (move_.state != MoveState::kWritesStopped) {
      return absl::FailedPreconditionError(
          absl::StrCat("map ", info_.name, ": its tail is sent once its writes are stopped (SetMapMove STOP_WRITES)"));
    }
  }
  base::MutexLock lock(&tail_mutex_);
  if (!tail_) {
    return absl::FailedPreconditionError(absl::StrCat(
        "map ", info_.name, " records no tail (no online copy was started since it opened): copy it again"));
  }
  if (!tail_->given_up.empty()) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info_.name, ": its tail was given up (", tail_->given_up, "): copy it again"));
  }
  std::vector<TailRecord> out;
  for (const TailRecord& r : tail_->records) {
    if (r.lsn > after) out.push_back(r);
  }
  return out;
}

absl::Status MapStoreImpl::ApplyTail(uint64_t after, std::span<const TailRecord> tail) {
  {
    base::MutexLock lock(&queue_mutex_);
    if (move_.state != MoveState::kIncoming) {
      return absl::FailedPreconditionError(absl::StrCat("map ", info_.name, " is not a move's copy waiting for its tail"));
    }
    if (move_.snapshot_lsn != after) {
      return absl::FailedPreconditionError(absl::StrCat("map ", info_.name, "'s snapshot is at LSN ", move_.snapshot_lsn,
                                                        "; the tail continues one at LSN ", after));
    }
  }
  std::vector<std::future<absl::StatusOr<BatchAck>>> acks;
  std::vector<std::shared_ptr<std::promise<absl::StatusOr<BatchAck>>>> promises;
  for (const TailRecord& r : tail) {
    auto batch = DecodeBatch(r.batch);
    if (!batch.ok()) {
      return absl::DataLossError(absl::StrCat("map ", info_.name, ": tail batch at LSN ", r.lsn, ": ",
                                              batch.status().message()));
    }
    auto promise = std::make_shared<std::promise<absl::StatusOr<BatchAck>>>();
    acks.push_back(promise->get_future());
    if (absl::Status s = Enqueue(*std::move(batch), [promise](absl::StatusOr<BatchAck> ack) { promise->set_value(std::move(ack)); },
                                 /*tail=*/true);
        !s.ok()) {
      for (size_t i = 0; i + 1 < acks.size(); ++i) acks[i].wait();
      return absl::Status(s.code(), absl::StrCat("map ", info_.name, ": tail batch at LSN ", r.lsn, ": ", s.message()));
    }
  }
  absl::Status status;
  for (size_t i = 0; i < acks.size(); ++i) {
    absl::StatusOr<BatchAck> ack = acks[i].get();
    if (!status.ok()) continue;
    if (!ack.ok()) {
      status = ack.status();
    } else if (ack->duplicate || !ack->error.ok()) {
      // The snapshot had it already, or another batch under its (writer, sequence): the tail does
      // not continue this snapshot, and the copy's deduplication windows would not be the source's.
      status = absl::DataLossError(absl::StrCat("map ", info_.name, ": tail batch at LSN ", tail[i].lsn,
                                                " does not follow the snapshot (",
                                                ack->duplicate ? "applied already" : ack->error.message(), ")"));
    }
  }
  if (!status.ok()) return status;
  if (absl::Status s = Checkpoint(); !s.ok()) return s;
  base::MutexLock lock(&queue_mutex_);
  if (absl::Status s = options_.env->Unlink(IncomingPath(dir_)); !s.ok() && !absl::IsNotFound(s)) return s;
  move_ = MoveStatus{};
  return absl::OkStatus();
}

void MapStoreImpl::Latch(const absl::Status& status) {
  std::vector<std::function<void()>> room;
  {
    base::MutexLock lock(&queue_mutex_);
    if (!write_error_.ok()) return;
    // A full disk stays ResourceExhausted; any other fault (an I/O error) is Unavailable: the map
    // takes no writes until an operator fixes the cause and reopens it. The message keeps the cause.
    const bool full = status.code() == absl::StatusCode::kResourceExhausted;
    write_error_ = absl::Status(
        full ? status.code() : absl::StatusCode::kUnavailable,
        absl::StrCat("map ", info_.name,
                     " refuses writes after a storage error (acknowledged data is kept; "
                     "restart fremend once it is fixed): ",
                     full ? "" : absl::StrCat(absl::StatusCodeToString(status.code()), ": "), status.message()));
    room.swap(room_waiters_);
  }
  // Waiters for room would otherwise wait for ever (the queue may stay full of batches that will
  // fail): they resubmit and learn the error.
  for (auto& f : room) f();
}

void MapStoreImpl::CommitLoop() {
  for (;;) {
    Stage stage;
    std::vector<std::function<void()>> room;
    bool closing;
    {
      base::MutexLock lock(&queue_mutex_);
      while (queue_.empty() && !closing_ && controls_.empty()) queue_ready_.Wait(&queue_mutex_);
      while (!queue_.empty()) {
        queued_observations_ -= queue_.front().batch.observation_count();
        stage.group.push_back(std::move(queue_.front()));
        queue_.pop_front();
      }
      stage.controls.swap(controls_);
      room.swap(room_waiters_);  // the queue was just emptied: there is room
      closing = closing_;
    }
    for (auto& f : room) f();
    stage.final = closing && stage.group.empty();
    absl::Status status;
    {
      base::MutexLock lock(&queue_mutex_);
      status = write_error_;
    }
    // 1. Log the new batches and publications, then sync once for all of them (group commit).
    if (status.ok()) {
      base::MutexLock wal(&wal_mutex_);
      const uint64_t before = wal_->last_lsn();
      LogGroup(stage.group);
      stage.group_lsn = wal_->last_lsn();
      for (Control& c : stage.controls) {
        if (c.kind != Control::Kind::kPublish) continue;
        const char record[] = {kPublishRecord};
        c.lsn = wal_->Append({reinterpret_cast<const uint8_t*>(record), 1});
        // A publication cannot be carried by a tail (batches only): a copy in progress is redone.
        GiveUpTail("an update job published during the copy");
      }
      const absl::Time sync_start = absl::Now();
      status = wal_->Sync();
      const uint64_t records = wal_->last_lsn() - before;
      if (status.ok() && records > 0) observer_->LogSynced(records, absl::Now() - sync_start);
    }
    if (!status.ok()) {
      // Nothing of this stage is durable: answer it now. No checkpoint runs from now on (see
      // StartCheckpoint); reads go on.
      Latch(status);
      status = WriteError();
      for (Pending& p : stage.group) p.done(status);
      stage.group.clear();
      std::erase_if(stage.controls, [&](Control& c) {
        if (c.kind != Control::Kind::kPublish) return false;
        c.done(status);
        return true;
      });
    }
    // 2. Hand over to the applier; at most one stage waits, which bounds what is logged but not
    // yet applied (and so acknowledged late).
    const bool final = stage.final;
    {
      base::MutexLock lock(&stage_mutex_);
      while (!stages_.empty()) stage_changed_.Wait(&stage_mutex_);
      stages_.push_back(std::move(stage));
    }
    stage_changed_.SignalAll();
    if (final) return;
  }
}

void MapStoreImpl::LogGroup(std::vector<Pending>& group) {
  base::MutexLock lock(&dedup_mutex_);
  for (Pending& p : group) {
    const absl::StatusOr<bool> seen = dedup_.Seen(p.batch.writer_id, p.batch.sequence, p.fingerprint);
    if (!seen.ok() || *seen) {
      p.ack = BatchAck{};
      p.ack.sequence = p.batch.sequence;
      p.ack.duplicate = seen.ok();
      if (!seen.ok()) {
        p.ack.error =
            absl::Status(seen.status().code(), absl::StrCat("map ", info_.name, ": ", seen.status().message()));
      }
      continue;
    }
    dedup_.Record(p.batch.writer_id, p.batch.sequence, p.fingerprint);
    p.ack.lsn = wal_->Append({reinterpret_cast<const uint8_t*>(p.record.data()), p.record.size()});
    CaptureTail(p.ack.lsn, p.record);
  }
}

void MapStoreImpl::ApplyLoop() {
  for (;;) {
    Stage stage;
    {
      base::ReleasableMutexLock lock(&stage_mutex_);
      if (publication_.has_value() && stages_.empty() && !publication_held_) {
        // Publish a slice, then look for batches again: they wait at most one slice.
        lock.Release();
        ContinuePublication();
        continue;
      }
      while (stages_.empty()) stage_changed_.Wait(&stage_mutex_);
      stage = std::move(stages_.front());
      stages_.pop_front();
    }
    stage_changed_.SignalAll();
    ApplyGroup(stage.group);
    if (!stage.group.empty()) publication_held_ = false;
    applied_lsn_ = std::max(applied_lsn_, stage.group_lsn);
    for (Control& c : stage.controls) {
      if (c.kind == Control::Kind::kPublish) {
        applied_lsn_ = c.lsn;
        StartPublication(std::move(c));
      } else {
        waiting_checkpoints_.push_back(std::move(c));
      }
    }
    if (stage.final) FinishPublication();
    // A checkpoint waits for the publication in progress: taken halfway, it would record states
    // published after the publication's log record as if that record had not been applied.
    if (!publication_.has_value()) {
      // Asked for (a caller waits, or the map closes): now. Due by the log's size: unless the
      // previous checkpoint is still being written — the log is dropped once it is.
      const bool asked = !waiting_checkpoints_.empty() || stage.final;
      const bool due = wal_->bytes() >= options_.checkpoint_log_bytes && !CheckpointWriting();
      if (asked || due) {
        StartCheckpoint(applied_lsn_, std::move(waiting_checkpoints_));
        waiting_checkpoints_.clear();
      }
    }
    if (stage.final) {
      WaitCheckpointWrite();
      return;
    }
  }
}

void MapStoreImpl::ApplyToShard(uint32_t s, const Pending& pending, const ScanContext& scan) const {
  const std::span<const uint64_t> keys = pending.keys[s];
  const std::span<const float> values = pending.values[s];
  if (pending.runs.empty()) {
    shards_[s]->Apply(scan, keys, values);
    return;
  }
  shards_[s]->ApplyHistory(settings_->periods, pending.runs[s], keys, values);
}

void MapStoreImpl::ApplyGroup(std::vector<Pending>& group) {
  // Every shard folds in its part of every batch, in batch order.
  std::vector<const Pending*> fresh;
  for (const Pending& p : group) {
    if (!p.ack.duplicate && p.ack.error.ok()) fresh.push_back(&p);
  }
  std::vector<ScanContext> scans;
  scans.reserve(fresh.size());
  uint64_t observations = 0;
  for (const Pending* p : fresh) {
    scans.emplace_back(settings_->periods, p->batch.time);
    observations += p->batch.observation_count();
  }
  if (!fresh.empty()) {
    workers_->RunOnAll([&](uint32_t s) {
      for (size_t b = 0; b < fresh.size(); ++b) {
        ApplyToShard(s, *fresh[b], scans[b]);
        if (!fresh[b]->labels[s].empty()) shards_[s]->ApplyLabels(fresh[b]->labels[s]);
      }
    }, observations >= kParallelApplyObservations);
  }
  for (const Pending* p : fresh) {
    IndexLabels(p->batch.labels);
    applied_dedup_.Record(p->batch.writer_id, p->batch.sequence, p->fingerprint);
  }
  // Durable and visible: acknowledge.
  for (Pending& p : group) {
    observer_->BatchAnswered(p.ack);
    p.done(p.ack);
  }
}

void MapStoreImpl::IndexLabels(std::span<const StateLabel> labels) {
  if (labels.empty()) return;
  base::MutexLock lock(&groups_mutex_);
  for (const StateLabel& l : labels) {
    if (l.group.empty()) continue;
    std::vector<uint64_t>& members = groups_[l.group];
    if (std::find(members.begin(), members.end(), l.key) == members.end()) members.push_back(l.key);
  }
}

void MapStoreImpl::StartPublication(Control control) {
  // The committer has logged and synced the publication's record already.
  FinishPublication();
  std::vector<uint64_t> marked(shards_.size());
  workers_->RunOnAll([&](uint32_t s) { marked[s] = shards_[s]->BeginPublication(); });
  publication_total_ = 0;
  for (uint64_t n : marked) publication_total_ += n;
  publication_ = std::move(control);
  publication_held_ = options_.publication_waits_for_a_batch;
  if (publication_->progress) publication_->progress(0, publication_total_);
  if (publication_total_ == 0) FinishPublication();
}

void MapStoreImpl::ContinuePublication() {
  // A slice bounds how long a batch that arrives meanwhile waits to be applied and acknowledged.
  constexpr auto kSlice = std::chrono::milliseconds(20);
  std::vector<uint8_t> finished(shards_.size());
  workers_->RunOnAll([&](uint32_t s) { finished[s] = shards_[s]->ContinuePublication(kSlice); });
  uint64_t done = 0;
  for (const auto& shard : shards_) done += shard->publication_done();
  if (publication_->progress) publication_->progress(done, publication_total_);
  if (std::all_of(finished.begin(), finished.end(), [](uint8_t f) { return f != 0; })) {
    publication_->done(publication_total_);
    publication_.reset();
  }
}

void MapStoreImpl::FinishPublication() {
  while (publication_.has_value()) ContinuePublication();
}

void MapStoreImpl::StartCheckpoint(uint64_t lsn, std::vector<Control> waiting) {
  WaitCheckpointWrite();
  // After a write error nothing more is written (LevelDB's bg_error_): the disk misbehaves, and
  // every applied batch is in the log already, which the next recovery replays.
  if (absl::Status error = WriteError(); !error.ok()) {
    for (Control& c : waiting) c.done(error);
    return;
  }
  auto images = std::make_shared<std::vector<Shard::CheckpointImage>>(shards_.size());
  workers_->RunOnAll([&](uint32_t s) { (*images)[s] = shards_[s]->PrepareCheckpoint(lsn, applied_dedup_); });
  checkpoint_write_ = std::async(std::launch::async, [this, lsn, images, waiting = std::move(waiting)]() mutable {
    const absl::Status status = WriteCheckpoint(lsn, *images);
    images.reset();  // the encoded states can be large: free them before answering
    for (Control& c : waiting) c.done(status.ok() ? absl::StatusOr<uint64_t>(0) : status);
  });
}

bool MapStoreImpl::CheckpointWriting() const {
  return checkpoint_write_.valid() &&
         checkpoint_write_.wait_for(std::chrono::seconds(0)) != std::future_status::ready;
}

void MapStoreImpl::WaitCheckpointWrite() {
  if (checkpoint_write_.valid()) checkpoint_write_.get();
}

absl::Status MapStoreImpl::WriteCheckpoint(uint64_t lsn, std::vector<Shard::CheckpointImage>& images) {
  // No backup copies the shards while they change, so that every copy is at one log position.
  base::MutexLock backup(&backup_mutex_);
  if (absl::Status error = WriteError(); !error.ok()) return error;  // latched meanwhile: see StartCheckpoint
  const absl::Time start = absl::Now();
  std::vector<absl::Status> writes(shards_.size());
  ParallelForShards(shards_.size(), [&](size_t s) { writes[s] = shards_[s]->WriteCheckpoint(images[s]); });
  absl::Status status;
  for (const absl::Status& w : writes) {
    if (status.ok()) status = w;
  }
  if (status.ok()) {
    base::MutexLock wal(&wal_mutex_);
    status = wal_->DropThrough(lsn);
  }
  if (status.ok()) written_lsn_ = lsn;
  // Reader slots of processes that died while reading (a backup tool, mdb_stat) would pin old
  // pages forever; clearing them with every checkpoint bounds the file's growth.
  for (const auto& shard : shards_) (void)shard->env().ClearStaleReaders();
  if (!status.ok()) {
    Latch(status);
    return status;
  }
  uint64_t bytes = 0;
  for (const Shard::CheckpointImage& image : images) bytes += ImageBytes(image);
  observer_->Checkpointed(bytes, absl::Now() - start);
  return status;
}

namespace {

// Appends each position i of `keys` to at[ShardOf(keys[i], shards)]. With the shard count a
// std::integral_constant, for the usual power of two the hash's modulo is a mask, not a division per
// key (which was most of this loop's cost for a batched Predict).
template <typename ShardCount>
void SplitPositions(std::span<const uint64_t> keys, ShardCount shards, std::vector<std::vector<uint32_t>>& at) {
  for (size_t i = 0; i < keys.size(); ++i) at[ShardOf(keys[i], shards)].push_back(static_cast<uint32_t>(i));
}

template <uint32_t kShards>
using Shards = std::integral_constant<uint32_t, kShards>;

}  // namespace

std::vector<std::vector<uint32_t>> MapStoreImpl::PositionsByShard(std::span<const uint64_t> keys) const {
  const uint32_t shards = info_.shards;
  std::vector<std::vector<uint32_t>> at(shards);
  // Bricks are spread evenly, but a small batch strays from the mean: room for 1/8 more.
  for (auto& positions : at) positions.reserve(keys.size() / shards + keys.size() / (8 * shards) + 16);
  switch (shards) {
    case 1: SplitPositions(keys, Shards<1>{}, at); break;
    case 2: SplitPositions(keys, Shards<2>{}, at); break;
    case 4: SplitPositions(keys, Shards<4>{}, at); break;
    case 8: SplitPositions(keys, Shards<8>{}, at); break;
    default: SplitPositions(keys, shards, at);
  }
  return at;
}

std::vector<float> MapStoreImpl::PredictKeys(std::span<const uint64_t> keys, std::span<const double> times,
                                             const PredictOptions& options, uint8_t* observed) const {
  std::vector<float> out(keys.size() * times.size());
  const std::vector<std::vector<uint32_t>> at = PositionsByShard(keys);
  for (size_t j = 0; j < times.size(); ++j) {
    const model::PhasorTable table(settings_->periods, times[j]);
    float* row = out.data() + j * keys.size();
    uint8_t* observed_now = j == 0 ? observed : nullptr;
    ParallelForShards(
        shards_.size(), [&](size_t s) { shards_[s]->PredictKeys(keys, at[s], table, options, row, observed_now); },
        /*parallel=*/keys.size() >= kParallelPredictions);
  }
  return out;
}

std::vector<float> MapStoreImpl::Predict(std::span<const uint64_t> keys, std::span<const double> times,
                                         const PredictOptions& options) const {
  return PredictKeys(keys, times, options, nullptr);
}

std::vector<float> MapStoreImpl::PredictWithObserved(std::span<const uint64_t> keys, std::span<const double> times,
                                                     const PredictOptions& options,
                                                     std::vector<uint8_t>& observed) const {
  if (times.empty()) {  // no time to predict at, but the caller still asks which keys were observed
    observed = Observed(keys);
    return {};
  }
  observed.assign(keys.size(), 0);
  return PredictKeys(keys, times, options, observed.data());
}

absl::Status MapStoreImpl::CheckBox(const CellBox& box) const {
  if (info_.kind != MapKind::kGrid) {
    return absl::FailedPreconditionError(absl::StrCat("map ", info_.name, " is not a grid: it has no boxes"));
  }
  static constexpr const char* kAxes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (box.lo[a] >= box.hi[a] || box.hi[a] > info_.grid.size[a]) {
      return absl::OutOfRangeError(absl::StrCat("box along ", kAxes[a], " must satisfy lo < hi ≤ ", info_.grid.size[a],
                                                ", got [", box.lo[a], ", ", box.hi[a], ")"));
    }
  }
  return absl::OkStatus();
}

absl::Status MapStoreImpl::PredictBox(const CellBox& box, double t, const PredictOptions& options,
                                  std::vector<float>& out) const {
  if (absl::Status s = CheckBox(box); !s.ok()) return s;
  out.resize(box.cell_count());
  return PredictBox(box, t, options, std::span<float>(out));
}

absl::Status MapStoreImpl::PredictBox(const CellBox& box, double t, const PredictOptions& options,
                                  std::span<float> out) const {
  return PredictBoxInto(box, t, options, out);
}

absl::Status MapStoreImpl::PredictBox(const CellBox& box, double t, const PredictOptions& options,
                                  std::span<uint8_t> out) const {
  return PredictBoxInto(box, t, options, out);
}

template <typename T>
absl::Status MapStoreImpl::PredictBoxInto(const CellBox& box, double t, const PredictOptions& options,
                                          std::span<T> out) const {
  if (absl::Status s = CheckBox(box); !s.ok()) return s;
  if (out.size() != box.cell_count()) {
    return absl::InvalidArgumentError(
        absl::StrCat("out holds ", out.size(), " values for a box of ", box.cell_count(), " cells"));
  }
  const model::PhasorTable table(settings_->periods, t);
  // The shards write every cell of their bricks; the cells of bricks none holds are filled after,
  // rather than every cell before (a 1M-cell FLOAT box's fill was 4% of a region's daemon time).
  const BoxBricks bricks(box, info_.grid.keys().brick_size());
  std::vector<uint8_t> held(bricks.size(), 0);
  ParallelForShards(
      shards_.size(), [&](size_t s) { shards_[s]->PredictBox(box, table, options, out.data(), held.data()); },
      /*parallel=*/box.cell_count() >= (1u << 16));
  bricks.FillUnheld(held.data(), CellValue<T>(kUnobservedProbability), out.data());
  return absl::OkStatus();
}

absl::StatusOr<BoxSeries> MapStoreImpl::PlanBoxSeries(const CellBox& box, double t,
                                                      const PredictOptions& options) const {
  if (absl::Status s = CheckBox(box); !s.ok()) return s;
  const model::PhasorTable table(settings_->periods, t);
  BoxSeries plan;
  plan.box = box;
  plan.options = options;
  plan.constant.assign(box.cell_count(), kUnobservedProbability);
  constexpr uint32_t kConstant = UINT32_MAX;
  std::vector<uint32_t> dynamic(box.cell_count(), kConstant);
  ParallelForShards(
      shards_.size(),
      [&](size_t s) { shards_[s]->PredictBoxConstant(box, table, options, plan.constant.data(), dynamic.data()); },
      /*parallel=*/box.cell_count() >= (1u << 16));
  const GridKeys keys = info_.grid.keys();
  const uint64_t nx = box.hi[0] - box.lo[0], ny = box.hi[1] - box.lo[1];
  plan.shards.resize(shards_.size());
  for (uint64_t i = 0; i < dynamic.size(); ++i) {
    if (dynamic[i] == kConstant) continue;
    const uint64_t key = keys.Key(static_cast<uint32_t>(box.lo[0] + i % nx), static_cast<uint32_t>(box.lo[1] + i / nx % ny),
                                  static_cast<uint32_t>(box.lo[2] + i / (nx * ny)));
    BoxSeries::ShardPart& part = plan.shards[ShardOf(key, info_.shards)];
    part.dynamic.push_back(dynamic[i]);
    part.at.push_back(static_cast<uint32_t>(plan.varying.size()));
    plan.varying.push_back(static_cast<uint32_t>(i));
    plan.varying_keys.push_back(key);
  }
  // In record order within each shard, so that the kernel reads the models front to back.
  for (BoxSeries::ShardPart& part : plan.shards) {
    std::vector<uint32_t> order(part.dynamic.size());
    for (uint32_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return part.dynamic[a] < part.dynamic[b]; });
    BoxSeries::ShardPart sorted;
    for (const uint32_t k : order) {
      sorted.dynamic.push_back(part.dynamic[k]);
      sorted.at.push_back(part.at[k]);
    }
    part = std::move(sorted);
  }
  return plan;
}

void MapStoreImpl::PredictBoxSeries(const BoxSeries& plan, std::span<const double> times,
                                    std::vector<float>& out) const {
  const size_t n = plan.varying_keys.size();
  out.resize(times.size() * n);
  std::vector<model::PhasorTable> tables;
  tables.reserve(times.size());
  for (double t : times) tables.emplace_back(settings_->periods, t);
  ParallelForShards(
      shards_.size(),
      [&](size_t s) {
        shards_[s]->PredictDynamic(plan.shards[s].dynamic, plan.shards[s].at, tables, plan.options, out.data(), n);
      },
      /*parallel=*/out.size() >= kParallelPredictions);
}

std::optional<StateSnapshot> MapStoreImpl::Snapshot(uint64_t key) const { return ShardFor(key).Snapshot(key); }

std::vector<uint8_t> MapStoreImpl::Observed(std::span<const uint64_t> keys) const {
  std::vector<uint8_t> out(keys.size());
  const std::vector<std::vector<uint32_t>> at = PositionsByShard(keys);
  for (size_t s = 0; s < shards_.size(); ++s) shards_[s]->ObservedKeys(keys, at[s], out.data());
  return out;
}

absl::StatusOr<std::vector<uint64_t>> MapStoreImpl::GroupMembers(const std::string& group) const {
  base::MutexLock lock(&groups_mutex_);
  auto it = groups_.find(group);
  if (it == groups_.end()) return absl::NotFoundError(absl::StrCat("map ", info_.name, " has no group \"", group, "\""));
  return it->second;
}

absl::StatusOr<std::vector<StateLabel>> MapStoreImpl::Labels(const std::string& group) const {
  std::vector<StateLabel> labels;
  if (group.empty()) {
    for (const auto& shard : shards_) {
      shard->ForEachLabel([&](uint64_t key, const std::string& name, const std::string& its_group) {
        labels.push_back(StateLabel{key, name, its_group});
      });
    }
  } else {
    auto members = GroupMembers(group);
    if (!members.ok()) return members.status();
    labels.reserve(members->size());
    for (uint64_t key : *members) {
      // A member's label can only have been replaced by a later batch naming it again; its group
      // then still says whether it belongs here.
      if (auto label = Label(key); label && label->second == group) {
        labels.push_back(StateLabel{key, label->first, label->second});
      }
    }
  }
  std::sort(labels.begin(), labels.end(), [](const StateLabel& a, const StateLabel& b) {
    return a.name != b.name ? a.name < b.name : a.key < b.key;
  });
  return labels;
}

absl::StatusOr<std::vector<std::pair<uint64_t, float>>> MapStoreImpl::TopN(const std::string& group, double t, size_t n,
                                                                      const PredictOptions& options) const {
  auto members = GroupMembers(group);
  if (!members.ok()) return members.status();
  const model::PhasorTable table(settings_->periods, t);
  std::vector<std::pair<uint64_t, float>> ranked;
  ranked.reserve(members->size());
  for (uint64_t key : *members) ranked.emplace_back(key, ShardFor(key).Predict(key, table, options));
  const size_t keep = std::min(n, ranked.size());
  std::partial_sort(ranked.begin(), ranked.begin() + keep, ranked.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  ranked.resize(keep);
  return ranked;
}

MapStats MapStoreImpl::Stats() const {
  MapStats stats;
  stats.totals.order_histogram.assign(settings_->max_order + 1, 0);
  for (const auto& shard : shards_) stats.totals += shard->Stats();
  {
    // The committer owns the log; its counters are read racily but only for reporting.
    stats.log_bytes = wal_->bytes();
    stats.last_lsn = wal_->durable_lsn();
  }
  if (stats.totals.disk_bytes > 0) {
    stats.compression_ratio = static_cast<double>(stats.totals.observations) / 8.0 / stats.totals.disk_bytes;
  }
  if (stats.totals.estimation_observed > 0) {
    stats.estimation_error = static_cast<double>(stats.totals.estimation_wrong) / stats.totals.estimation_observed;
  }
  if (stats.totals.lossless_prediction_observed > 0) {
    stats.lossless_prediction_error =
        static_cast<double>(stats.totals.lossless_prediction_wrong) / stats.totals.lossless_prediction_observed;
  }
  if (stats.totals.prediction_error_states > 0) {
    stats.mean_prediction_error = stats.totals.prediction_error_sum / stats.totals.prediction_error_states;
  }
  {
    base::MutexLock lock(&last_update_mutex_);
    stats.last_update = last_update_;
  }
  {
    base::MutexLock lock(&queue_mutex_);
    stats.queued_observations = queued_observations_;
  }
  for (const auto& shard : shards_) {
    stats.lmdb_map_size_bytes += shard->env().map_size();
    stats.lmdb_growths += shard->env().growths();
    stats.lmdb_readers += shard->env().readers();
  }
  return stats;
}

absl::StatusOr<uint64_t> MapStoreImpl::Backup(const std::string& dir, uint64_t* lsn) {
  if (absl::Status s = MakeDir(dir); !s.ok()) return s;
  if (absl::Status s = Checkpoint(); !s.ok()) return s;
  // No checkpoint can run while this is held, so every shard's copy is at the same log position.
  base::MutexLock backup(&backup_mutex_);
  if (lsn != nullptr) *lsn = written_lsn_;
  for (uint32_t i = 0; i < shards_.size(); ++i) {
    if (absl::Status s = shards_[i]->env().CopyTo(ShardDir(dir, i)); !s.ok()) return s;
  }
  if (absl::Status s = WriteFileAtomically(options_.env, dir + "/map.info", EncodeMapInfo(info_)); !s.ok()) return s;
  {
    // The last update job's record comes along, so that a restored (or moved) map reports it.
    base::MutexLock lock(&last_update_mutex_);
    if (last_update_) {
      if (absl::Status s = WriteUpdateRecord(options_.env, LastUpdatePath(dir), *last_update_); !s.ok()) return s;
    }
  }
  uint64_t bytes = 0;
  std::error_code error;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir, error)) {
    if (entry.is_regular_file(error)) bytes += entry.file_size(error);
  }
  return bytes;
}

VerifyReport MapStoreImpl::Verify(absl::Time deadline) {
  base::MutexLock backup(&backup_mutex_);
  VerifyOptions options;
  options.isolate = true;
  options.live = true;
  options.deadline = deadline;
  return VerifyMap(dir_, info_, options);
}

}  // namespace fremen::storage
