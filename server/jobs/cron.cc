#include "server/jobs/cron.h"

#include <array>
#include <cstdint>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace fremen::server {

namespace {

struct FieldSpec {
  const char* name;
  int min;
  int max;
};

constexpr std::array<FieldSpec, 5> kFields = {{
    {"minute", 0, 59},
    {"hour", 0, 23},
    {"day of month", 1, 31},
    {"month", 1, 12},
    {"day of week", 0, 7},
}};

absl::StatusOr<int> ParseNumber(absl::string_view text, const FieldSpec& field) {
  int value = 0;
  if (!absl::SimpleAtoi(text, &value)) {
    return absl::InvalidArgumentError(absl::StrCat(field.name, ": \"", text, "\" is not a number"));
  }
  if (value < field.min || value > field.max) {
    return absl::InvalidArgumentError(
        absl::StrCat(field.name, ": ", value, " is outside [", field.min, ", ", field.max, "]"));
  }
  return value;
}

// The values one field selects, as flags over [0, field.max]; `any` says the field was "*".
absl::Status ParseField(absl::string_view text, const FieldSpec& field, std::vector<bool>& selected, bool& any) {
  selected.assign(field.max + 1, false);
  any = text == "*";
  for (absl::string_view item : absl::StrSplit(text, ',')) {
    int step = 1;
    if (const size_t slash = item.find('/'); slash != absl::string_view::npos) {
      if (!absl::SimpleAtoi(item.substr(slash + 1), &step) || step < 1) {
        return absl::InvalidArgumentError(
            absl::StrCat(field.name, ": step \"", item.substr(slash + 1), "\" is not a positive number"));
      }
      item = item.substr(0, slash);
    }
    int lo = field.min;
    int hi = field.max;
    if (item != "*") {
      const size_t dash = item.find('-');
      auto first = ParseNumber(item.substr(0, dash), field);
      if (!first.ok()) return first.status();
      lo = hi = *first;
      if (dash != absl::string_view::npos) {
        auto last = ParseNumber(item.substr(dash + 1), field);
        if (!last.ok()) return last.status();
        hi = *last;
        if (hi < lo) return absl::InvalidArgumentError(absl::StrCat(field.name, ": range \"", item, "\" is empty"));
      } else if (step > 1) {
        hi = field.max;  // "a/n": from a to the end in steps of n
      }
    }
    for (int v = lo; v <= hi; v += step) selected[v] = true;
  }
  return absl::OkStatus();
}

template <size_t N>
std::bitset<N> ToBits(const std::vector<bool>& selected, int offset = 0) {
  std::bitset<N> bits;
  for (size_t v = 0; v < selected.size(); ++v) {
    if (selected[v]) bits.set((v + offset) % N);
  }
  return bits;
}

int Weekday(absl::CivilDay day) {
  switch (absl::GetWeekday(day)) {
    case absl::Weekday::sunday: return 0;
    case absl::Weekday::monday: return 1;
    case absl::Weekday::tuesday: return 2;
    case absl::Weekday::wednesday: return 3;
    case absl::Weekday::thursday: return 4;
    case absl::Weekday::friday: return 5;
    case absl::Weekday::saturday: return 6;
  }
  return 0;
}

}  // namespace

absl::StatusOr<CronSchedule> CronSchedule::Parse(absl::string_view text) {
  const std::vector<absl::string_view> fields = absl::StrSplit(text, ' ', absl::SkipWhitespace());
  if (fields.size() != kFields.size()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "\"", text, "\" has ", fields.size(), " fields; a schedule has 5: minute hour day-of-month month day-of-week"));
  }
  CronSchedule schedule;
  schedule.text_ = std::string(text);
  std::vector<bool> selected;
  bool any = false;
  for (size_t i = 0; i < kFields.size(); ++i) {
    if (absl::Status s = ParseField(fields[i], kFields[i], selected, any); !s.ok()) return s;
    switch (i) {
      case 0: schedule.minutes_ = ToBits<60>(selected); break;
      case 1: schedule.hours_ = ToBits<24>(selected); break;
      case 2: schedule.days_of_month_ = ToBits<32>(selected); schedule.day_of_month_any_ = any; break;
      case 3: schedule.months_ = ToBits<13>(selected); break;
      case 4: schedule.days_of_week_ = ToBits<7>(selected); schedule.day_of_week_any_ = any; break;  // 7 → 0
    }
  }
  return schedule;
}

bool CronSchedule::MatchesDay(absl::CivilDay day) const {
  if (!months_.test(day.month())) return false;
  const bool dom = days_of_month_.test(day.day());
  const bool dow = days_of_week_.test(Weekday(day));
  if (day_of_month_any_ || day_of_week_any_) return dom && dow;  // "*" selects every day
  return dom || dow;
}

bool CronSchedule::Matches(absl::CivilMinute minute) const {
  return MatchesDay(absl::CivilDay(minute)) && hours_.test(minute.hour()) && minutes_.test(minute.minute());
}

absl::Time CronSchedule::Next(absl::Time after, absl::TimeZone zone) const {
  const absl::CivilMinute start = absl::ToCivilMinute(after, zone) + 1;
  constexpr int kSearchDays = 8 * 366;  // covers every leap day
  for (absl::CivilDay day(start); day < absl::CivilDay(start) + kSearchDays; ++day) {
    if (!MatchesDay(day)) continue;
    for (int h = 0; h < 24; ++h) {
      if (!hours_.test(h)) continue;
      for (int m = 0; m < 60; ++m) {
        const absl::CivilMinute candidate(day.year(), day.month(), day.day(), h, m);
        if (candidate < start || !minutes_.test(m)) continue;
        // kSkipped (a spring-forward gap) lands on the transition; kRepeated takes the first.
        const absl::TimeZone::TimeInfo info = zone.At(candidate);
        const absl::Time t = info.kind == absl::TimeZone::TimeInfo::SKIPPED ? info.trans : info.pre;
        if (t > after) return t;
      }
    }
  }
  return absl::InfiniteFuture();
}

}  // namespace fremen::server
