#include "client/fremenctl/cli_args.h"

#include <cmath>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace fremen::client {

absl::StatusOr<double> ParseTimeArg(absl::string_view text, absl::Time now) {
  if (text == "now") return absl::ToDoubleSeconds(now - absl::UnixEpoch());
  double seconds = 0;
  if (absl::SimpleAtod(text, &seconds)) {
    if (std::isfinite(seconds)) return seconds;
  } else {
    absl::Time time;
    std::string error;
    if (absl::ParseTime(absl::RFC3339_full, text, &time, &error)) return absl::ToDoubleSeconds(time - absl::UnixEpoch());
  }
  return absl::InvalidArgumentError(absl::StrCat("time \"", text,
                                                 "\" is not \"now\", seconds since 1970, or RFC 3339 like "
                                                 "2026-11-23T08:00:00Z"));
}

namespace {

// Two or three comma-separated numbers; z is 0 when absent.
absl::StatusOr<std::vector<double>> ParseTriple(absl::string_view text, absl::string_view what, bool integers) {
  std::vector<std::string> parts = absl::StrSplit(text, ',');
  std::vector<double> values;
  const auto bad = [&] {
    return absl::InvalidArgumentError(absl::StrCat(what, " \"", text, "\" is not X,Y or X,Y,Z",
                                                   integers ? " (non-negative whole cell indices)" : " (metres)"));
  };
  if (parts.size() < 2 || parts.size() > 3) return bad();
  for (const std::string& part : parts) {
    if (integers) {
      uint32_t v = 0;
      if (!absl::SimpleAtoi(part, &v)) return bad();
      values.push_back(v);
    } else {
      double v = 0;
      if (!absl::SimpleAtod(part, &v) || !std::isfinite(v)) return bad();
      values.push_back(v);
    }
  }
  if (values.size() == 2) values.push_back(0);
  return values;
}

}  // namespace

absl::StatusOr<Cell> ParseCellArg(absl::string_view text) {
  auto v = ParseTriple(text, "cell", /*integers=*/true);
  if (!v.ok()) return v.status();
  return Cell{static_cast<uint32_t>((*v)[0]), static_cast<uint32_t>((*v)[1]), static_cast<uint32_t>((*v)[2])};
}

absl::StatusOr<Point> ParsePointArg(absl::string_view text) {
  auto v = ParseTriple(text, "point", /*integers=*/false);
  if (!v.ok()) return v.status();
  return Point{(*v)[0], (*v)[1], (*v)[2]};
}

absl::StatusOr<StateSet> ParseStateArgs(const StateArgs& args) {
  const int kinds = !args.cells.empty() + !args.points.empty() + !args.ids.empty() + !args.names.empty();
  if (kinds != 1) {
    return absl::InvalidArgumentError(
        "name the states with one of --cell X,Y[,Z], --point X,Y[,Z] (grid maps), --id N or --name S (generic "
        "maps); each may repeat, but kinds cannot be mixed");
  }
  if (!args.ids.empty()) return StateSet::Ids(args.ids);
  if (!args.names.empty()) return StateSet::Names(args.names);
  if (!args.cells.empty()) {
    std::vector<Cell> cells;
    for (const std::string& text : args.cells) {
      auto cell = ParseCellArg(text);
      if (!cell.ok()) return cell.status();
      cells.push_back(*cell);
    }
    return StateSet::Cells(cells);
  }
  std::vector<Point> points;
  for (const std::string& text : args.points) {
    auto point = ParsePointArg(text);
    if (!point.ok()) return point.status();
    points.push_back(*point);
  }
  return StateSet::Points(points);
}

absl::StatusOr<std::vector<double>> ParseTimeArgs(const std::vector<std::string>& texts, absl::Time now) {
  if (texts.empty()) return absl::InvalidArgumentError("give at least one --time");
  std::vector<double> times;
  for (const std::string& text : texts) {
    auto time = ParseTimeArg(text, now);
    if (!time.ok()) return time.status();
    times.push_back(*time);
  }
  return times;
}

}  // namespace fremen::client
