// The calls in flight, so that shutdown waits for them and only them. gRPC's Shutdown(deadline)
// also waits for every client connection to close — idle robots keep theirs open — so it would
// always take the whole grace period; instead the daemon drains the calls it knows about here and
// then shuts gRPC down at once. While draining, new calls are refused with UNAVAILABLE, the status
// clients retry. A call that lasts as long as its client wants (an ingest stream) is also told to
// wind down when draining starts, so that it does not hold shutdown for the whole grace period.
// Thread-safety: every method may be called from any thread.
#pragma once

#include <cstdint>
#include <memory>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "absl/time/time.h"

namespace fremen::server {

class CallTracker {
 public:
  // A long-lived call, told when the daemon drains.
  class Drainable {
   public:
    // Stop taking new work, finish what was acknowledged, then end the call (with UNAVAILABLE, the
    // status clients retry). Called at most once, on the draining thread, without the tracker's
    // lock: it may call the tracker.
    virtual void WindDown() = 0;

   protected:
    ~Drainable() = default;
  };

  // Registers a call; Unavailable while draining. Every successful Begin needs one End.
  absl::Status Begin() ABSL_LOCKS_EXCLUDED(mutex_);
  void End() ABSL_LOCKS_EXCLUDED(mutex_);
  // Begin() for a long-lived call, which Drain asks to wind down unless it has ended (or is gone:
  // the tracker holds it weakly). The id for EndStream; Unavailable while draining.
  absl::StatusOr<uint64_t> BeginStream(std::weak_ptr<Drainable> call) ABSL_LOCKS_EXCLUDED(mutex_);
  // End() for a call begun with BeginStream.
  void EndStream(uint64_t id) ABSL_LOCKS_EXCLUDED(mutex_);
  // Refuses new calls from now on and waits until none is in flight or `timeout` has passed. The
  // calls still in flight (0 when drained).
  int64_t Drain(absl::Duration timeout) ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  base::Mutex mutex_;
  base::CondVar idle_;
  int64_t in_flight_ ABSL_GUARDED_BY(mutex_) = 0;
  bool draining_ ABSL_GUARDED_BY(mutex_) = false;
  uint64_t next_stream_id_ ABSL_GUARDED_BY(mutex_) = 0;
  absl::flat_hash_map<uint64_t, std::weak_ptr<Drainable>> streams_ ABSL_GUARDED_BY(mutex_);
};

}  // namespace fremen::server
