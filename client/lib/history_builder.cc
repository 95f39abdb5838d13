#include "client/lib/history_builder.h"

#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"

namespace fremen::client {

namespace {
constexpr double kMaxTime = 1e13;
}  // namespace

HistoryBuilder HistoryBuilder::ForId(uint64_t id, const std::string& name, const std::string& group) {
  HistoryBuilder builder;
  builder.kind_ = Kind::kOneState;
  v1::HistoryObservations* history = builder.request_.mutable_history();
  history->add_ids(id);
  if (!name.empty() || !group.empty()) {
    history->add_names(name);
    history->add_groups(group);
  }
  return builder;
}

HistoryBuilder HistoryBuilder::ForName(const std::string& name, const std::string& group) {
  HistoryBuilder builder;
  builder.kind_ = Kind::kOneState;
  builder.request_.mutable_history()->add_names(name);
  if (!group.empty()) builder.request_.mutable_history()->add_groups(group);
  return builder;
}

void HistoryBuilder::Misuse(const char* what) {
  if (error_.ok()) error_ = absl::InvalidArgumentError(what);
}

HistoryBuilder& HistoryBuilder::Add(double time, float value) {
  if (kind_ != Kind::kOneState) {
    Misuse("Add is for one state's history (HistoryBuilder::ForId or ForName); use AddState with an id");
    return *this;
  }
  request_.mutable_history()->add_times(time);
  request_.mutable_history()->add_values(value);
  return *this;
}

HistoryBuilder& HistoryBuilder::AddState(double time, uint64_t id, float value) {
  if (kind_ != Kind::kManyStates) {
    Misuse("AddState is for a history of many states (HistoryBuilder()); this one is of one state: use Add");
    return *this;
  }
  request_.mutable_history()->add_times(time);
  request_.mutable_history()->add_ids(id);
  request_.mutable_history()->add_values(value);
  return *this;
}

absl::StatusOr<Scan> HistoryBuilder::Build() {
  absl::Status error = error_;
  const v1::HistoryObservations& history = request_.history();
  if (error.ok() && history.values_size() == 0) {
    error = absl::InvalidArgumentError("the history has no observations: add some first");
  }
  for (int i = 0; error.ok() && i < history.times_size(); ++i) {
    const double t = history.times(i);
    if (!(t >= 0 && t <= kMaxTime)) {
      error = absl::InvalidArgumentError(
          absl::StrCat("time ", i, " is ", t, ": a time must be finite seconds since the Unix epoch in [0, 1e13]"));
    }
  }
  Scan scan;
  // Empty again, for the same state(s).
  v1::IngestRequest next;
  if (kind_ == Kind::kOneState) {
    *next.mutable_history()->mutable_ids() = history.ids();
    *next.mutable_history()->mutable_names() = history.names();
    *next.mutable_history()->mutable_groups() = history.groups();
  }
  if (error.ok()) {
    scan.observations = static_cast<uint64_t>(history.values_size());
    scan.request = std::move(request_);
  }
  request_ = std::move(next);
  error_ = absl::OkStatus();
  if (!error.ok()) return error;
  return scan;
}

}  // namespace fremen::client
