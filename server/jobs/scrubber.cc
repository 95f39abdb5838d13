#include "server/jobs/scrubber.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "server/rpc/logging.h"

namespace fremen::server {

namespace {

// Linux keeps the nice value and the I/O priority per thread, and fork() copies the calling
// thread's: lowering this thread's lowers the verifier's child processes too. Best effort: a
// failure leaves the scrub at normal priority and says so.
void LowerThisThreadsPriority() {
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  if (setpriority(PRIO_PROCESS, tid, 19) != 0) {
    DaemonLog()->warn("scrub: cannot lower its CPU priority: {}", std::strerror(errno));
  }
  constexpr int kIoprioWhoProcess = 1, kIoprioClassIdle = 3, kIoprioClassShift = 13;
  if (syscall(SYS_ioprio_set, kIoprioWhoProcess, tid, kIoprioClassIdle << kIoprioClassShift) != 0) {
    DaemonLog()->warn("scrub: cannot lower its I/O priority: {}", std::strerror(errno));
  }
}

}  // namespace

Scrubber::Scrubber(Options options, const Clock& clock, MapLister list_maps, Check check)
    : options_(options), clock_(clock), list_maps_(std::move(list_maps)), check_(std::move(check)) {}

void Scrubber::Start() {
  base::MutexLock lock(&mutex_);
  if (!enabled()) {
    DaemonLog()->info("no background scrub (scrub_interval 0): maps are checked only on demand (CheckMap)");
    return;
  }
  if (thread_.joinable() || stopping_) return;
  next_ = clock_.Now() + options_.interval;
  DaemonLog()->info("background scrub every {}", absl::FormatDuration(options_.interval));
  thread_ = std::thread([this] { Run(); });
}

void Scrubber::Stop() {
  {
    base::MutexLock lock(&mutex_);
    stopping_ = true;
    next_ = absl::InfiniteFuture();
    wake_.SignalAll();
  }
  if (thread_.joinable()) thread_.join();
}

absl::Time Scrubber::NextPass() const {
  base::MutexLock lock(&mutex_);
  return next_;
}

std::vector<Scrubber::Result> Scrubber::Results() const {
  base::MutexLock lock(&mutex_);
  std::vector<Result> results;
  results.reserve(results_.size());
  for (const auto& [map, result] : results_) results.push_back(result);
  return results;
}

bool Scrubber::AwaitPasses(uint64_t passes, absl::Duration timeout) const {
  const absl::Time deadline = absl::Now() + timeout;
  base::MutexLock lock(&mutex_);
  while (passes_ < passes) {
    if (pass_done_.WaitWithDeadline(&mutex_, deadline)) return passes_ >= passes;  // timed out
  }
  return true;
}

void Scrubber::Run() {
  if (options_.low_priority) LowerThisThreadsPriority();
  base::MutexLock lock(&mutex_);
  while (!stopping_) {
    if (clock_.Now() < next_) {
      clock_.WaitUntil(wake_, mutex_, next_);
      continue;
    }
    mutex_.Unlock();
    Pass();
    mutex_.Lock();
    ++passes_;
    pass_done_.SignalAll();
    // From the end of this pass: a pass that takes longer than the interval is not followed at once
    // by the next one.
    if (!stopping_) next_ = clock_.Now() + options_.interval;
  }
}

void Scrubber::Pass() {
  auto maps = list_maps_();
  if (!maps.ok()) {
    DaemonLog()->warn("scrub skipped: cannot list the maps: {}", std::string(maps.status().message()));
    return;
  }
  {
    base::MutexLock lock(&mutex_);
    for (auto it = results_.begin(); it != results_.end();) {
      it = std::find(maps->begin(), maps->end(), it->first) == maps->end() ? results_.erase(it) : std::next(it);
    }
  }
  for (const std::string& map : *maps) {
    {
      base::MutexLock lock(&mutex_);
      if (stopping_) return;
    }
    Scrub(map);
  }
}

void Scrubber::Scrub(const std::string& map) {
  const absl::Time start = clock_.Now();
  auto report = check_(map, absl::Now() + options_.map_timeout);
  if (!report.ok()) {
    DaemonLog()->debug("scrub of map {} skipped: {}", map, std::string(report.status().message()));
    return;
  }
  Result result;
  result.map = map;
  result.finished = clock_.Now();
  result.took = result.finished - start;
  result.clean = report->clean();
  result.problem_count = report->problems.size();
  for (const storage::VerifyProblem& problem : report->problems) {
    if (result.problems.size() == kMaxProblemsKept) break;
    result.problems.push_back(problem);
  }
  for (const storage::ShardVerifyReport& shard : report->shards) result.records += shard.records;
  if (report->deadline_exceeded) {
    DaemonLog()->error("scrub of map {}: not finished within scrub_map_timeout {}: {}", map,
                       absl::FormatDuration(options_.map_timeout), storage::FormatProblem(report->problems.back()));
  } else if (result.clean) {
    DaemonLog()->info("scrub of map {}: clean ({} records)", map, result.records);
  } else {
    DaemonLog()->error("scrub of map {}: {} problems, first {}", map, result.problem_count,
                       storage::FormatProblem(report->problems.front()));
  }
  base::MutexLock lock(&mutex_);
  results_[map] = std::move(result);
}

}  // namespace fremen::server
