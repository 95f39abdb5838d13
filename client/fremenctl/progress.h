// How `fremenctl update --wait` shows an operation's progress: a bar redrawn in place on a terminal
// ("[######......] 1200/5000 states 24% 3400 states/s ETA 0:02"), plain lines otherwise (logs,
// cron mail), and the summary of a finished update. Pure formatting, unit-tested.
// Thread-safety: pure functions.
#pragma once

#include <string>

#include "fremen/v1/admin.pb.h"

namespace fremen::client {

// "0:07", "12:34", "1:02:03"; "?" when unknown (≤ 0 or not finite).
std::string FormatEta(double seconds);
// The bar, `width` characters between the brackets, and the figures.
std::string ProgressBar(const v1::Operation& op, int width = 30);
// "update of lab: running, 1200/5000 states (24%), 3400 states/s, ETA 0:02".
std::string ProgressLine(const v1::Operation& op);
// One line of `fremenctl operations list`: "operations/update-lab-2 lab done: 5000 states published
// (RunUpdate)"; a queued or running one shows its progress, a failed one its error.
std::string OperationLine(const v1::Operation& op);
// The result of a finished update, several lines; or why it failed or was cancelled.
std::string UpdateSummary(const v1::Operation& op);

}  // namespace fremen::client
