#include "server/jobs/update_scheduler.h"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "server/rpc/logging.h"

namespace fremen::server {

namespace {

std::string Format(absl::Time t, absl::TimeZone zone) {
  return t == absl::InfiniteFuture() ? "never" : absl::FormatTime("%Y-%m-%d %H:%M:%S %Z", t, zone);
}

}  // namespace

UpdateScheduler::UpdateScheduler(Options options, const Clock& clock, MapLister list_maps, Trigger trigger)
    : options_(std::move(options)), clock_(clock), list_maps_(std::move(list_maps)), trigger_(std::move(trigger)) {
  const absl::Time now = clock_.Now();
  if (options_.schedule) entries_.push_back({*options_.schedule, "", options_.schedule->Next(now, options_.zone)});
  for (const auto& [map, schedule] : options_.overrides) {
    if (schedule) entries_.push_back({*schedule, map, schedule->Next(now, options_.zone)});
  }
}

void UpdateScheduler::Start() {
  base::MutexLock lock(&mutex_);
  if (entries_.empty() || thread_.joinable() || stopping_) {
    if (entries_.empty()) DaemonLog()->info("no update schedule: updates run only on demand (RunUpdate)");
    return;
  }
  DaemonLog()->info("update schedule \"{}\" in {}{}; next run {}", options_.schedule ? options_.schedule->text() : "",
              options_.zone.name(),
              options_.overrides.empty() ? "" : absl::StrCat(", ", options_.overrides.size(), " maps with their own"),
              Format(NextRunLocked(), options_.zone));
  thread_ = std::thread([this] { Run(); });
}

void UpdateScheduler::Stop() {
  {
    base::MutexLock lock(&mutex_);
    stopping_ = true;
    wake_.SignalAll();
  }
  if (thread_.joinable()) thread_.join();
}

absl::Time UpdateScheduler::NextRun() const {
  base::MutexLock lock(&mutex_);
  return NextRunLocked();
}

absl::Time UpdateScheduler::NextRunLocked() const {
  absl::Time next = absl::InfiniteFuture();
  for (const Entry& e : entries_) next = std::min(next, e.next);
  return next;
}

void UpdateScheduler::Run() {
  base::MutexLock lock(&mutex_);
  while (!stopping_) {
    const absl::Time now = clock_.Now();
    std::vector<std::string> due;
    for (Entry& entry : entries_) {
      if (entry.next > now) continue;
      due.push_back(entry.map);
      // From now, not from the run that was due: a jump over several runs gives one.
      entry.next = entry.schedule.Next(now, options_.zone);
    }
    if (!due.empty()) {
      mutex_.Unlock();
      Fire(due);
      mutex_.Lock();
      DaemonLog()->info("next scheduled update {}", Format(NextRunLocked(), options_.zone));
      continue;
    }
    clock_.WaitUntil(wake_, mutex_, NextRunLocked());
  }
}

void UpdateScheduler::Fire(const std::vector<std::string>& due) {
  auto maps = list_maps_();
  if (!maps.ok()) {
    DaemonLog()->warn("scheduled update skipped: cannot list the maps: {}", std::string(maps.status().message()));
    return;
  }
  const auto is_due = [&](const std::string& map) { return std::find(due.begin(), due.end(), map) != due.end(); };
  const bool default_due = options_.schedule && is_due("");
  size_t started = 0;
  for (const std::string& map : *maps) {
    bool run = default_due;
    if (auto o = options_.overrides.find(map); o != options_.overrides.end()) run = is_due(map);
    if (!run) continue;
    trigger_(map);
    ++started;
  }
  DaemonLog()->info("scheduled update: started for {} of {} maps", started, maps->size());
}

absl::StatusOr<UpdateScheduler::Options> SchedulerOptionsFromConfig(const ServerConfig& config) {
  UpdateScheduler::Options options;
  if (!config.update_schedule.empty()) {
    auto schedule = CronSchedule::Parse(config.update_schedule);
    if (!schedule.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("update_schedule: ", schedule.status().message()));
    }
    options.schedule = *std::move(schedule);
  }
  if (config.update_time_zone == "local") {
    options.zone = absl::LocalTimeZone();
  } else if (!absl::LoadTimeZone(config.update_time_zone, &options.zone)) {
    return absl::InvalidArgumentError(absl::StrCat("update_time_zone: unknown time zone \"", config.update_time_zone, "\""));
  }
  for (const MapSchedule& map : config.update_map_schedules) {
    std::optional<CronSchedule>& entry = options.overrides[map.map];
    if (map.schedule.empty()) continue;  // none: on demand only
    auto schedule = CronSchedule::Parse(map.schedule);
    if (!schedule.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("update_map_schedules: map \"", map.map, "\": ", schedule.status().message()));
    }
    entry = *std::move(schedule);
  }
  return options;
}

}  // namespace fremen::server
