// The update schedule: at each time of a cron schedule (server/jobs/cron.h) in a time zone — config
// update_schedule and update_time_zone, default daily at 00:00 local time — the update job of every
// map is started (as an operation, server/jobs/operations.h, so a map whose update still runs is not
// updated twice). A map may have its own schedule, or none, instead of the default (Options::
// overrides).
//
// Times are wall-clock times in the zone: a run whose minute a daylight-saving jump skips happens
// at the instant the jump lands on (02:30 on a spring-forward night in Europe/Prague runs at 03:00
// CEST); a minute that a fall-back repeats runs once, the first time. A clock that jumps over
// several runs (a suspended machine, NTP) gives one run, not one per time missed, and runs missed
// while the daemon was down are not made up (as cron). The thread waits through a Clock
// (server/jobs/clock.h), so tests drive it with a fake clock and no sleeps.
// Thread-safety: Start and Stop from one thread; NextRun from any thread; the trigger is called on
// the scheduler's thread and must not block for long.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "base/mutex.h"
#include "absl/time/time.h"
#include "server/jobs/clock.h"
#include "server/daemon/config.h"
#include "server/jobs/cron.h"

namespace fremen::server {

class UpdateScheduler {
 public:
  struct Options {
    // The schedule of every map without an override; nullopt = none.
    std::optional<CronSchedule> schedule;
    absl::TimeZone zone = absl::UTCTimeZone();
    // Per map: its own schedule, or nullopt for no scheduled update (on demand only).
    absl::flat_hash_map<std::string, std::optional<CronSchedule>> overrides;
  };
  // The maps to update now; an error skips the run (and is logged).
  using MapLister = std::function<absl::StatusOr<std::vector<std::string>>()>;
  using Trigger = std::function<void(const std::string& map)>;

  // `clock` must outlive the scheduler. The next runs are computed from clock.Now() here.
  UpdateScheduler(Options options, const Clock& clock, MapLister list_maps, Trigger trigger);
  ~UpdateScheduler() { Stop(); }
  UpdateScheduler(const UpdateScheduler&) = delete;
  UpdateScheduler& operator=(const UpdateScheduler&) = delete;

  // Starts the thread; nothing runs before. A scheduler with no schedule at all starts none.
  void Start() ABSL_LOCKS_EXCLUDED(mutex_);
  // Stops and joins the thread. Idempotent.
  void Stop() ABSL_LOCKS_EXCLUDED(mutex_);

  // The next time any map's update is due; InfiniteFuture when none is scheduled.
  absl::Time NextRun() const ABSL_LOCKS_EXCLUDED(mutex_);

 private:
  // One schedule and its next run: the default one (map empty) or a map's override.
  struct Entry {
    CronSchedule schedule;
    std::string map;
    absl::Time next;
  };

  void Run() ABSL_LOCKS_EXCLUDED(mutex_);
  // Starts the updates of the due entries, named by their maps ("" for the default schedule).
  // Called without the lock: the lister and the triggers may take long.
  void Fire(const std::vector<std::string>& due) ABSL_LOCKS_EXCLUDED(mutex_);
  absl::Time NextRunLocked() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);

  const Options options_;
  const Clock& clock_;
  const MapLister list_maps_;
  const Trigger trigger_;

  mutable base::Mutex mutex_;
  base::CondVar wake_;
  std::vector<Entry> entries_ ABSL_GUARDED_BY(mutex_);
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  std::thread thread_;  // Start and Stop's (one thread)
};

// The schedules from the config (update_schedule, update_time_zone, update_map_schedules).
// InvalidArgument naming the setting (the config's parsers have checked them already).
absl::StatusOr<UpdateScheduler::Options> SchedulerOptionsFromConfig(const ServerConfig& config);

}  // namespace fremen::server
