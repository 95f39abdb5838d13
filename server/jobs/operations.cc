#include "server/jobs/operations.h"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/rpc/logging.h"

namespace fremen::server {

namespace {

constexpr char kPublishingMessage[] =
    "publishing: the new models are one record of the map's log, applied whole and repeated whole by "
    "recovery, so the publication runs to its end";

std::string Seconds(absl::Duration d) { return absl::StrFormat("%.3g s", absl::ToDoubleSeconds(d)); }

}  // namespace

bool JobControl::BeginPublishing() { return registry_->BeginPublishing(id_); }
void JobControl::Progress(uint64_t done, uint64_t total) { registry_->Progress(id_, done, total); }

OperationRegistry::OperationRegistry(UpdateJob job, const Clock& clock, Options options)
    : job_(std::move(job)), clock_(clock), options_(options), thread_([this] { Run(); }) {}

absl::StatusOr<OperationView> OperationRegistry::StartUpdate(const std::string& map, absl::string_view trigger) {
  base::MutexLock lock(&mutex_);
  if (stopping_) return absl::UnavailableError("fremend is stopping; no new operations");
  if (auto active = active_by_map_.find(map); active != active_by_map_.end()) {
    return operations_.at(active->second).view;  // idempotent: the update already under way
  }
  PruneLocked();
  const uint64_t id = next_id_++;
  Operation& op = operations_[id];
  op.view.id = id;
  op.view.name = absl::StrCat("operations/update-", map, "-", id);
  op.view.map = map;
  op.view.trigger = std::string(trigger);
  op.view.create_time = clock_.Now();
  op.view.message = queue_.empty() ? "queued" : absl::StrCat("queued behind ", queue_.size(), " other update(s)");
  by_name_[op.view.name] = id;
  active_by_map_[map] = id;
  queue_.push_back(id);
  work_.Signal();
  return op.view;
}

const OperationRegistry::Operation* OperationRegistry::FindLocked(const std::string& name) const {
  auto it = by_name_.find(name);
  return it == by_name_.end() ? nullptr : &operations_.at(it->second);
}

absl::StatusOr<OperationView> OperationRegistry::Get(const std::string& name) const {
  base::MutexLock lock(&mutex_);
  const Operation* op = FindLocked(name);
  if (op == nullptr) {
    return absl::NotFoundError(absl::StrCat("no operation named \"", name, "\" (finished ones are kept for ",
                                            absl::FormatDuration(options_.keep_finished), ")"));
  }
  return op->view;
}

absl::StatusOr<OperationRegistry::Page> OperationRegistry::List(const std::string& map, bool running_only,
                                                                 size_t page_size,
                                                                 const std::string& page_token) const {
  // The token is the id of the last operation of the previous page: ids only grow, so a page
  // boundary stays put while operations start and old ones are dropped.
  uint64_t before = UINT64_MAX;
  if (!page_token.empty() && (!absl::SimpleAtoi(page_token, &before) || before == 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("page_token: \"", page_token, "\" is not a next_page_token of ListOperations"));
  }
  Page page;
  base::MutexLock lock(&mutex_);
  for (auto it = operations_.lower_bound(before); it != operations_.begin();) {
    const OperationView& view = (--it)->second.view;
    if (!map.empty() && view.map != map) continue;
    if (running_only && view.done()) continue;
    if (page.operations.size() == page_size) {
      page.next_page_token = absl::StrCat(page.operations.back().id);
      break;
    }
    page.operations.push_back(view);
  }
  return page;
}

absl::StatusOr<OperationView> OperationRegistry::Cancel(const std::string& name) {
  base::MutexLock lock(&mutex_);
  auto it = by_name_.find(name);
  if (it == by_name_.end()) {
    return absl::NotFoundError(absl::StrCat("no operation named \"", name, "\""));
  }
  Operation& op = operations_.at(it->second);
  switch (op.view.stage) {
    case OperationStage::kDone:
      break;
    case OperationStage::kQueued:
      op.view.cancel_requested = true;
      std::erase(queue_, op.view.id);
      FinishLocked(op, absl::CancelledError("cancelled before it started"));
      break;
    case OperationStage::kRunning:
      // The job stops at BeginPublishing, moments from now; the client polls for the end.
      op.view.cancel_requested = true;
      op.view.message = "cancelling: stops before it publishes";
      break;
    case OperationStage::kPublishing:
      op.view.cancel_requested = true;
      op.view.message = absl::StrCat("cannot cancel: ", kPublishingMessage);
      break;
  }
  return op.view;
}

size_t OperationRegistry::running() const {
  base::MutexLock lock(&mutex_);
  return active_by_map_.size();
}

std::vector<OperationView> OperationRegistry::LastUpdates() const {
  base::MutexLock lock(&mutex_);
  absl::flat_hash_map<std::string, const OperationView*> last;
  for (const auto& [id, op] : operations_) {  // oldest first: later ones replace earlier ones
    if (op.view.done()) last[op.view.map] = &op.view;
  }
  std::vector<OperationView> out;
  for (const auto& [map, view] : last) out.push_back(*view);
  std::sort(out.begin(), out.end(), [](const OperationView& a, const OperationView& b) { return a.map < b.map; });
  return out;
}

void OperationRegistry::Stop() {
  {
    base::MutexLock lock(&mutex_);
    if (stopping_ && !thread_.joinable()) return;
    stopping_ = true;
    for (uint64_t id : queue_) FinishLocked(operations_.at(id), absl::CancelledError("fremend stopped before it started"));
    queue_.clear();
    work_.SignalAll();
  }
  if (thread_.joinable()) thread_.join();
}

void OperationRegistry::Run() {
  while (true) {
    uint64_t id;
    {
      base::MutexLock lock(&mutex_);
      while (!stopping_ && queue_.empty()) work_.Wait(&mutex_);
      if (queue_.empty()) return;  // stopping, nothing left
      id = queue_.front();
      queue_.erase(queue_.begin());
    }
    RunOne(id);
  }
}

void OperationRegistry::RunOne(uint64_t id) {
  std::string map;
  {
    base::MutexLock lock(&mutex_);
    Operation& op = operations_.at(id);
    op.view.stage = OperationStage::kRunning;
    op.view.start_time = clock_.Now();
    op.view.message = "running: reading the map's statistics";
    map = op.view.map;
    DaemonLog()->info("update of map {} started ({}, {})", map, op.view.name, op.view.trigger);
  }
  JobControl control(this, id, map);
  absl::StatusOr<UpdateFigures> outcome = job_(control);
  base::MutexLock lock(&mutex_);
  Operation& op = operations_.at(id);
  if (op.view.stage != OperationStage::kPublishing && !outcome.ok() && op.view.cancel_requested) {
    outcome = absl::CancelledError("cancelled before it published");
  }
  FinishLocked(op, std::move(outcome));
}

bool OperationRegistry::BeginPublishing(uint64_t id) {
  base::MutexLock lock(&mutex_);
  Operation& op = operations_.at(id);
  if (op.view.cancel_requested || stopping_) {
    op.view.cancel_requested = true;
    return false;
  }
  op.view.stage = OperationStage::kPublishing;
  op.view.message = kPublishingMessage;
  op.publish_start = op.last_log = clock_.Now();
  return true;
}

void OperationRegistry::Progress(uint64_t id, uint64_t done, uint64_t total) {
  base::ReleasableMutexLock lock(&mutex_);
  Operation& op = operations_.at(id);
  const absl::Time now = clock_.Now();
  OperationView& view = op.view;
  // Reports from several shard threads may arrive out of order: progress never goes back.
  view.states_done = std::max(view.states_done, done);
  view.states_total = total;
  done = view.states_done;
  const double elapsed = absl::ToDoubleSeconds(now - op.publish_start);
  view.rate = elapsed > 0 ? done / elapsed : 0;
  view.eta_seconds = view.rate > 0 && total > done ? (total - done) / view.rate : 0;
  if (view.stage != OperationStage::kPublishing || now - op.last_log < options_.progress_log_interval) return;
  op.last_log = now;
  const std::string line =
      absl::StrFormat("update of map %s: %d/%d states (%.0f%%), %.3g states/s, ~%.3g s left", view.map, done, total,
                      total > 0 ? 100.0 * done / total : 100.0, view.rate, view.eta_seconds);
  lock.Release();
  DaemonLog()->info("{}", line);
}

void OperationRegistry::FinishLocked(Operation& op, absl::StatusOr<UpdateFigures> outcome) {
  OperationView& view = op.view;
  view.stage = OperationStage::kDone;
  view.end_time = clock_.Now();
  view.eta_seconds = 0;
  active_by_map_.erase(view.map);
  const absl::Duration duration =
      view.start_time == absl::InfinitePast() ? absl::ZeroDuration() : view.end_time - view.start_time;
  if (!outcome.ok()) {
    view.error = outcome.status();
    view.message = std::string(outcome.status().message());
    if (absl::IsCancelled(view.error)) {
      DaemonLog()->info("update of map {} cancelled ({}): {}", view.map, view.name, view.message);
    } else {
      DaemonLog()->error("update of map {} failed after {} ({}): {}", view.map, Seconds(duration), view.name, view.message);
    }
    if (options_.on_finished) options_.on_finished(view);
    return;
  }
  outcome->duration = duration;
  view.states_total = std::max(view.states_total, outcome->states_published);
  view.states_done = view.states_total;
  if (const double s = absl::ToDoubleSeconds(duration); s > 0) view.rate = outcome->states_published / s;
  view.message = view.cancel_requested ? "done: the cancellation came while it was publishing, which runs to its end"
                                       : "done";
  view.result = *std::move(outcome);
  DaemonLog()->info("update of map {}: {} states in {}, ε_p {:.4g} → {:.4g}", view.map, view.result->states_published,
              Seconds(duration), view.result->prediction_error_before, view.result->prediction_error_after);
  if (options_.on_finished) options_.on_finished(view);
}

void OperationRegistry::PruneLocked() {
  const absl::Time horizon = clock_.Now() - options_.keep_finished;
  size_t finished = 0;
  for (const auto& [id, op] : operations_) finished += op.view.done();
  for (auto it = operations_.begin(); it != operations_.end();) {  // oldest first
    const OperationView& view = it->second.view;
    if (view.done() && (finished > options_.max_finished || view.end_time < horizon)) {
      --finished;
      by_name_.erase(view.name);
      it = operations_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace fremen::server
