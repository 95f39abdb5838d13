// The daemon's long-running operations: update jobs (docs/update-job.md), started by RunUpdate or
// the schedule, run one after another on the registry's own thread — never on a gRPC thread — and
// kept for a while after they end so that clients can poll them.
//
// An operation is named "operations/update-<map>-<n>" (n counts from 1 in each daemon run) and
// goes QUEUED → RUNNING (reading the map's statistics) → PUBLISHING → DONE. At most one update of
// a map is not done at any time: StartUpdate on a map with one returns that one, so two triggers
// make one job.
//
// Cancel: a queued operation ends at once (CANCELLED); a running one ends CANCELLED when it reaches
// JobControl::BeginPublishing; one that is publishing cannot be stopped — publication is one record
// of the map's log, applied whole by the store and repeated whole by recovery — so it finishes
// normally and says so in its message.
//
// Finished operations are kept for at least Options::keep_finished, unless more than
// Options::max_finished have finished (the oldest go first); both are enforced when an operation
// starts, so the list stays bounded. The log ("fremend" logger) gets a line when a job starts, progress
// lines every Options::progress_log_interval while it publishes, and its figures when it ends:
//   update of map lab: 1000000 states in 0.61 s, ε_p 0.213 → 0.177
// Thread-safety: every public method may be called from any thread.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "base/mutex.h"
#include "absl/time/time.h"
#include "server/jobs/clock.h"

namespace fremen::server {

// What an update did, from the map's statistics before and after.
struct UpdateFigures {
  uint64_t states_published = 0;
  absl::Duration duration;  // filled by the registry: from the start of RUNNING to the end
  // Dynamic states by selected order 0..L once published.
  std::vector<uint64_t> order_histogram;
  // Mean decayed ε_p at each state's selected order (docs/model.md, "Order selection"): before =
  // the orders the previous update chose, after = the orders this one chose.
  double prediction_error_before = 0;
  double prediction_error_after = 0;
};

enum class OperationStage { kQueued, kRunning, kPublishing, kDone };

// A copy of one operation's state, safe to read without the registry's lock.
struct OperationView {
  uint64_t id = 0;
  std::string name;
  std::string map;
  std::string trigger;  // who started it: "RunUpdate", "schedule"
  OperationStage stage = OperationStage::kQueued;
  absl::Time create_time;
  absl::Time start_time = absl::InfinitePast();  // RUNNING from; InfinitePast while queued
  absl::Time end_time = absl::InfinitePast();    // when done
  bool cancel_requested = false;
  // For the client: what is happening and why (e.g. why a cancellation did not stop it).
  std::string message;
  uint64_t states_done = 0;
  uint64_t states_total = 0;
  double rate = 0;         // states per second since publishing started
  double eta_seconds = 0;  // 0 = unknown
  absl::Status error;      // when done: OK, CANCELLED or the job's error
  std::optional<UpdateFigures> result;  // when done with OK

  bool done() const { return stage == OperationStage::kDone; }
};

class OperationRegistry;

// The running job's handle on its operation. Valid only during the job.
class JobControl {
 public:
  JobControl(OperationRegistry* registry, uint64_t id, std::string map) : registry_(registry), id_(id), map_(std::move(map)) {}

  const std::string& map() const { return map_; }
  // The point of no return: moves the operation to PUBLISHING, after which it cannot be
  // cancelled. False when it was cancelled (or the daemon is stopping): the job must return
  // without publishing (its status is then replaced by CANCELLED).
  bool BeginPublishing();
  // Publication progress; may be called from any thread, often (it is cheap). States done never
  // go back: a report older than one already seen changes only the total.
  void Progress(uint64_t done, uint64_t total);

 private:
  OperationRegistry* registry_;
  uint64_t id_;
  std::string map_;
};

// The work of an update: returns its figures (duration aside) or its error.
using UpdateJob = std::function<absl::StatusOr<UpdateFigures>(JobControl& control)>;

class OperationRegistry {
 public:
  struct Options {
    size_t max_finished = 256;
    absl::Duration keep_finished = absl::Hours(24);
    absl::Duration progress_log_interval = absl::Seconds(5);
    // Called with each operation as it ends (done, failed or cancelled), under the registry's
    // lock: it must be quick and must not call the registry (the metrics count it). Default: none.
    std::function<void(const OperationView&)> on_finished;
  };

  struct Page {
    std::vector<OperationView> operations;  // newest first
    std::string next_page_token;            // empty on the last page
  };

  // `clock` must outlive the registry. Starts the job thread.
  OperationRegistry(UpdateJob job, const Clock& clock, Options options);
  OperationRegistry(UpdateJob job, const Clock& clock) : OperationRegistry(std::move(job), clock, Options()) {}
  ~OperationRegistry() { Stop(); }
  OperationRegistry(const OperationRegistry&) = delete;
  OperationRegistry& operator=(const OperationRegistry&) = delete;

  // Queues an update of `map`, or returns the update of `map` not yet done. Unavailable once
  // stopping. The caller checks that the map exists.
  absl::StatusOr<OperationView> StartUpdate(const std::string& map, absl::string_view trigger)
      ABSL_LOCKS_EXCLUDED(mutex_);
  // NotFound for a name never given or no longer kept.
  absl::StatusOr<OperationView> Get(const std::string& name) const ABSL_LOCKS_EXCLUDED(mutex_);
  // Newest first; `map` empty = every map. `page_token` is a next_page_token of an earlier page
  // (InvalidArgument otherwise); page_size > 0.
  absl::StatusOr<Page> List(const std::string& map, bool running_only, size_t page_size,
                            const std::string& page_token) const ABSL_LOCKS_EXCLUDED(mutex_);
  // See the file comment. NotFound as Get; an operation already done is returned unchanged.
  absl::StatusOr<OperationView> Cancel(const std::string& name) ABSL_LOCKS_EXCLUDED(mutex_);

  // Operations not yet done.
  size_t running() const ABSL_LOCKS_EXCLUDED(mutex_);
  // For each map, its most recent finished update still kept.
  std::vector<OperationView> LastUpdates() const ABSL_LOCKS_EXCLUDED(mutex_);

  // Refuses new operations, cancels the queued ones, lets the running one finish (a publication
  // is short and atomic; a job not yet publishing is cancelled) and joins the thread. Idempotent.
  void Stop() ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  friend class JobControl;
  struct Operation {
    OperationView view;
    absl::Time publish_start = absl::InfinitePast();
    absl::Time last_log = absl::InfinitePast();
  };

  void Run() ABSL_LOCKS_EXCLUDED(mutex_);
  // Runs the job without the lock: the registry answers polls while it runs.
  void RunOne(uint64_t id) ABSL_LOCKS_EXCLUDED(mutex_);
  bool BeginPublishing(uint64_t id) ABSL_LOCKS_EXCLUDED(mutex_);
  void Progress(uint64_t id, uint64_t done, uint64_t total) ABSL_LOCKS_EXCLUDED(mutex_);
  // Ends an operation.
  void FinishLocked(Operation& op, absl::StatusOr<UpdateFigures> outcome) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  // Drops finished operations beyond the limits.
  void PruneLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  const Operation* FindLocked(const std::string& name) const ABSL_SHARED_LOCKS_REQUIRED(mutex_);

  const UpdateJob job_;
  const Clock& clock_;
  const Options options_;

  mutable base::Mutex mutex_;
  base::CondVar work_;
  std::map<uint64_t, Operation> operations_ ABSL_GUARDED_BY(mutex_);  // by id: oldest first
  absl::flat_hash_map<std::string, uint64_t> by_name_ ABSL_GUARDED_BY(mutex_);
  // The update not yet done, per map.
  absl::flat_hash_map<std::string, uint64_t> active_by_map_ ABSL_GUARDED_BY(mutex_);
  std::vector<uint64_t> queue_ ABSL_GUARDED_BY(mutex_);  // queued ids, oldest first
  uint64_t next_id_ ABSL_GUARDED_BY(mutex_) = 1;
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  std::thread thread_;
};

}  // namespace fremen::server
