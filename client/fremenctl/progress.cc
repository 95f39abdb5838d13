#include "client/fremenctl/progress.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace fremen::client {

namespace {

std::string StageName(const v1::Operation& op) {
  switch (op.stage()) {
    case v1::OPERATION_STAGE_QUEUED:
      return "queued";
    case v1::OPERATION_STAGE_RUNNING:
      return "running";
    case v1::OPERATION_STAGE_PUBLISHING:
      return "publishing";
    case v1::OPERATION_STAGE_DONE:
      return "done";
    default:
      return op.done() ? "done" : "running";
  }
}

// Percent done; 0 with no total yet.
double Percent(const v1::Progress& p) {
  return p.states_total() == 0 ? 0 : 100.0 * std::min(p.states_done(), p.states_total()) / p.states_total();
}

}  // namespace

std::string FormatEta(double seconds) {
  if (!std::isfinite(seconds) || seconds <= 0) return "?";
  const int64_t s = std::llround(seconds);
  if (s >= 3600) return absl::StrFormat("%d:%02d:%02d", s / 3600, s / 60 % 60, s % 60);
  return absl::StrFormat("%d:%02d", s / 60, s % 60);
}

std::string ProgressBar(const v1::Operation& op, int width) {
  const v1::Progress& p = op.progress();
  const int filled = static_cast<int>(std::lround(Percent(p) / 100 * width));
  return absl::StrFormat("[%s%s] %d/%d states %3.0f%% %.0f states/s ETA %s (%s)", std::string(filled, '#'),
                         std::string(width - filled, '.'), p.states_done(), p.states_total(), Percent(p), p.rate(),
                         FormatEta(p.eta_seconds()), StageName(op));
}

std::string ProgressLine(const v1::Operation& op) {
  const v1::Progress& p = op.progress();
  return absl::StrFormat("update of %s: %s, %d/%d states (%.0f%%), %.0f states/s, ETA %s", op.map(), StageName(op),
                         p.states_done(), p.states_total(), Percent(p), p.rate(), FormatEta(p.eta_seconds()));
}

std::string OperationLine(const v1::Operation& op) {
  std::string what;
  if (!op.done()) {
    what = absl::StrFormat("%d/%d states (%.0f%%)", op.progress().states_done(), op.progress().states_total(),
                           Percent(op.progress()));
  } else if (op.error().code() == 1 /* CANCELLED */) {
    what = "cancelled";
  } else if (op.error().code() != 0) {
    what = absl::StrCat("failed: ", op.error().message());
  } else {
    what = absl::StrCat(op.update().states_published(), " states published");
  }
  return absl::StrCat(op.name(), " ", op.map(), " ", StageName(op), ": ", what,
                      op.trigger().empty() ? "" : absl::StrCat(" (", op.trigger(), ")"));
}

std::string UpdateSummary(const v1::Operation& op) {
  if (op.error().code() == 1 /* CANCELLED */) {
    return absl::StrCat("update of ", op.map(), " (", op.name(), ") was cancelled",
                        op.error().message().empty() ? "" : ": ", op.error().message());
  }
  if (op.error().code() != 0) {
    return absl::StrCat("update of ", op.map(), " (", op.name(), ") failed: ", op.error().message());
  }
  const v1::UpdateResult& r = op.update();
  return absl::StrFormat(
      "update of %s (%s) done: %d states published in %.2f s\n"
      "orders: %s (dynamic states by selected order 0..L)\n"
      "prediction error: %.4f before, %.4f after",
      op.map(), op.name(), r.states_published(), r.duration_seconds(), absl::StrJoin(r.order_histogram(), " "),
      r.prediction_error_before(), r.prediction_error_after());
}

}  // namespace fremen::client
