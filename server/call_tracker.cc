#include "server/call_tracker.h"

#include "absl/time/clock.h"

namespace fremen::server {

absl::Status CallTracker::Begin() {
  std::lock_guard lock(mutex_);
  if (draining_) return absl::UnavailableError("fremend is shutting down; retry on another daemon or later");
  ++in_flight_;
  return absl::OkStatus();
}

void CallTracker::End() {
  std::lock_guard lock(mutex_);
  if (--in_flight_ == 0 && draining_) idle_.notify_all();
}

int64_t CallTracker::Drain(absl::Duration timeout) {
  std::unique_lock lock(mutex_);
  draining_ = true;
  idle_.wait_for(lock, absl::ToChronoNanoseconds(timeout), [this] { return in_flight_ == 0; });
  return in_flight_;
}

}  // namespace fremen::server
