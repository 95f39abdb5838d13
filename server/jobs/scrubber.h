// The background scrub: every `interval` (config scrub_interval; 0, the default, turns it off) the
// files of every served map are verified as CheckMap verifies them — every record of every shard
// read and checked in a child process, the write-ahead log replayed — one map after another, on a
// thread (and children) at the lowest CPU and I/O priority, so that a scrub takes longer rather than
// slowing ingest and queries. Its purpose is to find damage that nothing reads (a model no query has
// asked for since the disk flipped its bits) before a restart or a backup depends on it.
//
// One map's check is bounded by `map_timeout` (config scrub_map_timeout): a shard still being read
// then is reported "not verified" (its reading child is killed) and the pass goes on with the next
// map, so that a map whose files block the reader (a hung disk) neither stalls the scrub of the
// others nor holds back Stop — and so a daemon's shutdown — for longer than that.
//
// Nothing is repaired. Each map's latest result is kept (Results(), GetServerStatus map_scrubs) and
// logged: a clean pass at info, problems at error with the first one named. Failed maps are not
// scrubbed (they are not open; GetServerStatus lists them as failed already).
//
// The thread waits through a Clock (server/jobs/clock.h), so tests drive passes with a fake clock.
// Thread-safety: Start and Stop from one thread; Results, NextPass, AwaitPasses from any thread.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/btree_map.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "absl/time/time.h"
#include "server/jobs/clock.h"
#include "storage/verify.h"

namespace fremen::server {

class Scrubber {
 public:
  // A map's latest scrub.
  struct Result {
    std::string map;
    absl::Time finished;
    absl::Duration took;
    bool clean = false;
    uint64_t problem_count = 0;
    std::vector<storage::VerifyProblem> problems;  // the first kMaxProblemsKept
    uint64_t records = 0;                          // shard records read
  };
  static constexpr size_t kMaxProblemsKept = 20;

  struct Options {
    absl::Duration interval = absl::ZeroDuration();  // between the end of a pass and the next; 0 = off
    // Lower the scrub thread's CPU and I/O priority (nice 19, idle I/O class); its forked children
    // inherit them. Default true; tests of the schedule leave the test process alone.
    bool low_priority = true;
    // The longest one map's check may take (real time, as the reading child is killed by it).
    absl::Duration map_timeout = absl::Hours(1);
  };
  // The maps to scrub now; an error skips the pass (and is logged).
  using MapLister = std::function<absl::StatusOr<std::vector<std::string>>()>;
  // Verifies one map by `deadline`; an error (a map deleted meanwhile, a failed map) skips it.
  using Check = std::function<absl::StatusOr<storage::VerifyReport>(const std::string& map, absl::Time deadline)>;

  // `clock` must outlive the scrubber. The first pass is due one interval after Start.
  Scrubber(Options options, const Clock& clock, MapLister list_maps, Check check);
  ~Scrubber() { Stop(); }
  Scrubber(const Scrubber&) = delete;
  Scrubber& operator=(const Scrubber&) = delete;

  // Starts the thread; does nothing when the interval is 0.
  void Start() ABSL_LOCKS_EXCLUDED(mutex_);
  // Stops and joins the thread; a pass under way stops after the map it is verifying (so within
  // map_timeout). Idempotent.
  void Stop() ABSL_LOCKS_EXCLUDED(mutex_);

  bool enabled() const { return options_.interval > absl::ZeroDuration(); }
  // When the next pass starts; InfiniteFuture when off or stopped.
  absl::Time NextPass() const ABSL_LOCKS_EXCLUDED(mutex_);
  // Each map's latest result, in map name order (maps no longer listed are dropped at each pass).
  std::vector<Result> Results() const ABSL_LOCKS_EXCLUDED(mutex_);
  // Waits until `passes` passes have finished since Start, or `timeout` (real time) has passed;
  // returns whether they have. For tests, which move a fake clock and then wait for the thread.
  bool AwaitPasses(uint64_t passes, absl::Duration timeout) const ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  void Run() ABSL_LOCKS_EXCLUDED(mutex_);
  // Both called without the lock: a pass takes long, and NextPass/Results answer meanwhile.
  void Pass() ABSL_LOCKS_EXCLUDED(mutex_);
  void Scrub(const std::string& map) ABSL_LOCKS_EXCLUDED(mutex_);

  const Options options_;
  const Clock& clock_;
  const MapLister list_maps_;
  const Check check_;

  mutable base::Mutex mutex_;
  mutable base::CondVar wake_;       // Stop, the clock
  mutable base::CondVar pass_done_;  // AwaitPasses
  absl::Time next_ ABSL_GUARDED_BY(mutex_) = absl::InfiniteFuture();
  uint64_t passes_ ABSL_GUARDED_BY(mutex_) = 0;
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  absl::btree_map<std::string, Result> results_ ABSL_GUARDED_BY(mutex_);
  std::thread thread_;  // Start and Stop's (one thread)
};

}  // namespace fremen::server
