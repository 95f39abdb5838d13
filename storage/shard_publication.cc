// Shard's part of the update job (docs/update-job.md; see "the update job" in shard.h): which states a
// publication updates (those touched since their last one), publishing them a slice at a time so
// that the map's batches and readers are never held off for long, and keeping the touched flags
// across a checkpoint.
#include <algorithm>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"
#include "storage/shard.h"
#include "storage/shard_records.h"

namespace fremen::storage {

namespace {

// Incremental states are published this many at a time under the exclusive lock: about 10-30 µs
// of readers' wait per chunk at ~2M states/s, and the budget is checked between chunks. (Not named
// kChunk: inside Shard's methods that name is Shard::kChunk, the slot runs of 64 keys.)
constexpr size_t kStatesPerLock = 1024;

}  // namespace

void Shard::PublishState(uint32_t d, bool history_updated) {
  spectra_.Load(d, publish_scratch_);
  BeforeModelChange(d);
  publisher_.Publish(publish_scratch_, errors_.BestOrder(d, settings_.order_rule), models_, d);
  if (settings_.error_half_life == 0) errors_.Reset(d);  // "only since the last update"
  if (lossless_ && !history_updated) (void)lossless_histories_[d].Update(settings_.max_order);
  publish_flags_[d] = 0;
  // A publication changes the published model alone, unless it also resets the order errors or
  // transforms a lossless history: then the state's other records change too.
  if (settings_.error_half_life == 0 || lossless_) {
    MarkDirty(slot_of_[d]);
  } else {
    MarkPublishedDirty(slot_of_[d]);
  }
}

size_t Shard::BeginPublication() {
  if (publication_cursor_ < publication_list_.size()) {
    while (!ContinuePublication(std::chrono::hours(1))) {
    }
  }
  publication_list_.clear();
  publication_cursor_ = 0;
  for (uint32_t d = 0; d < publish_flags_.size(); ++d) {
    if (publish_flags_[d] & kTouched) {
      publish_flags_[d] |= kPending;
      publication_list_.push_back(d);
    }
  }
  publishing_ = !publication_list_.empty();
  return publication_list_.size();
}

bool Shard::ContinuePublication(std::chrono::nanoseconds budget) {
  const auto deadline = std::chrono::steady_clock::now() + budget;
  while (publication_cursor_ < publication_list_.size()) {
    if (lossless_) {
      // One state at a time, its transform computed outside the lock (this thread is the only
      // writer, so the history cannot change meanwhile): readers wait only for the swap.
      const uint32_t d = publication_list_[publication_cursor_++];
      if (publish_flags_[d] & kPending) {
        model::LosslessHistory updated = WritersHistory(d);
        (void)updated.Update(settings_.max_order);
        base::WriterMutexLock lock(&mutex_);
        std::swap(lossless_histories_[d], updated);
        PublishState(d, /*history_updated=*/true);
      }
    } else {
      const size_t end = std::min(publication_list_.size(), publication_cursor_ + kStatesPerLock);
      base::WriterMutexLock lock(&mutex_);
      for (; publication_cursor_ < end; ++publication_cursor_) {
        const uint32_t d = publication_list_[publication_cursor_];
        if (publish_flags_[d] & kPending) PublishState(d);  // else a batch published it first
      }
    }
    if (std::chrono::steady_clock::now() >= deadline) break;
  }
  const bool done = publication_cursor_ == publication_list_.size();
  if (done) publishing_ = false;
  return done;
}

size_t Shard::PublishAll(const std::function<void(uint64_t)>& progress) {
  const size_t count = BeginPublication();
  constexpr auto kSlice = std::chrono::milliseconds(20);
  for (bool done = count == 0; !done;) {
    done = ContinuePublication(kSlice);
    if (progress) progress(publication_cursor_);
  }
  return count;
}

std::string Shard::EncodeTouched() const {
  std::vector<uint64_t> keys;
  for (uint32_t d = 0; d < publish_flags_.size(); ++d) {
    if (publish_flags_[d] & kTouched) keys.push_back(slots_[slot_of_[d]].key);
  }
  std::sort(keys.begin(), keys.end());
  return shard_records::EncodeTouched(keys);
}

absl::Status Shard::DecodeTouched(std::string_view bytes) {
  std::fill(publish_flags_.begin(), publish_flags_.end(), 0);
  auto keys = shard_records::DecodeTouched(bytes);
  if (!keys.ok()) return keys.status();
  for (uint64_t key : *keys) {
    const uint32_t slot = FindSlot(key);
    if (slot == kNone || slots_[slot].dynamic == kNone) {
      return absl::DataLossError(absl::StrCat("touched states: state ", key, " is not a dynamic state of the shard"));
    }
    publish_flags_[slots_[slot].dynamic] = kTouched;
  }
  return absl::OkStatus();
}

}  // namespace fremen::storage
