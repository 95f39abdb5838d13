// A cron schedule: the five classic fields "minute hour day-of-month month day-of-week", each `*`,
// a number, a range `a-b`, a step `*/n` or `a-b/n`, or a comma-separated list of those. Numbers
// only (no names, no @macros). Day-of-week 0-7, where 0 and 7 are Sunday. As in cron, when both
// day fields are restricted a day matches if either does.
//
// Used for the daemon's update schedule (default "0 0 * * *": daily at midnight). Value type;
// thread-safe to share read-only.
#pragma once

#include <bitset>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/civil_time.h"
#include "absl/time/time.h"

namespace fremen::server {

class CronSchedule {
 public:
  // InvalidArgument naming the field ("hour: 24 is outside [0, 23]").
  static absl::StatusOr<CronSchedule> Parse(absl::string_view text);

  // Whether the schedule fires at this minute (local to the schedule's time zone).
  bool Matches(absl::CivilMinute minute) const;
  // The first minute after `after` at which it fires, in `zone`; InfiniteFuture when none within
  // eight years (e.g. "0 0 30 2 *"). A firing minute skipped by a daylight-saving jump is taken
  // at the instant the jump lands on.
  absl::Time Next(absl::Time after, absl::TimeZone zone) const;

  const std::string& text() const { return text_; }

 private:
  bool MatchesDay(absl::CivilDay day) const;

  std::string text_;
  std::bitset<60> minutes_;
  std::bitset<24> hours_;
  std::bitset<32> days_of_month_;  // 1..31
  std::bitset<13> months_;         // 1..12
  std::bitset<7> days_of_week_;    // 0..6, Sunday = 0
  bool day_of_month_any_ = true;
  bool day_of_week_any_ = true;
};

}  // namespace fremen::server
