// The calls in flight, so that shutdown waits for them and only them. gRPC's Shutdown(deadline)
// also waits for every client connection to close — idle robots keep theirs open — so it would
// always take the whole grace period; instead the daemon drains the calls it knows about here and
// then shuts gRPC down at once. While draining, new calls are refused with UNAVAILABLE, the status
// clients retry.
// Thread-safety: every method may be called from any thread.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "absl/status/status.h"
#include "absl/time/time.h"

namespace fremen::server {

class CallTracker {
 public:
  // Registers a call; Unavailable while draining. Every successful Begin needs one End.
  absl::Status Begin();
  void End();
  // Refuses new calls from now on and waits until none is in flight or `timeout` has passed. The
  // calls still in flight (0 when drained).
  int64_t Drain(absl::Duration timeout);

 private:
  std::mutex mutex_;
  std::condition_variable idle_;
  int64_t in_flight_ = 0;
  bool draining_ = false;
};

}  // namespace fremen::server
