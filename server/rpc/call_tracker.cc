#include "server/rpc/call_tracker.h"

#include <vector>

#include "absl/time/clock.h"

namespace fremen::server {

namespace {
absl::Status ShuttingDown() {
  return absl::UnavailableError("fremend is shutting down; retry on another daemon or later");
}
}  // namespace

absl::Status CallTracker::Begin() {
  base::MutexLock lock(&mutex_);
  if (draining_) return ShuttingDown();
  ++in_flight_;
  return absl::OkStatus();
}

void CallTracker::End() {
  base::MutexLock lock(&mutex_);
  if (--in_flight_ == 0 && draining_) idle_.SignalAll();
}

absl::StatusOr<uint64_t> CallTracker::BeginStream(std::weak_ptr<Drainable> call) {
  base::MutexLock lock(&mutex_);
  if (draining_) return ShuttingDown();
  ++in_flight_;
  streams_.emplace(++next_stream_id_, std::move(call));
  return next_stream_id_;
}

void CallTracker::EndStream(uint64_t id) {
  {
    base::MutexLock lock(&mutex_);
    streams_.erase(id);
  }
  End();
}

int64_t CallTracker::Drain(absl::Duration timeout) {
  std::vector<std::shared_ptr<Drainable>> streams;
  {
    base::MutexLock lock(&mutex_);
    draining_ = true;
    for (auto& [id, weak] : streams_) {
      if (auto stream = weak.lock()) streams.push_back(std::move(stream));
    }
    streams_.clear();
  }
  // Outside the lock: winding down may end the call at once.
  for (const auto& stream : streams) stream->WindDown();
  streams.clear();
  const absl::Time deadline = absl::Now() + timeout;
  base::MutexLock lock(&mutex_);
  while (in_flight_ != 0) {
    if (idle_.WaitWithDeadline(&mutex_, deadline)) break;  // timed out
  }
  return in_flight_;
}

}  // namespace fremen::server
