// Grid CSV reading (see grid_csv.h).
#include "client/formats/grid_csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "storage/model/observation.h"

namespace fremen::formats {

namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> SplitCommas(std::string_view line) {
  std::vector<std::string_view> fields;
  while (true) {
    const size_t comma = line.find(',');
    fields.push_back(Trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return fields;
    line.remove_prefix(comma + 1);
  }
}

bool ParseDouble(std::string_view token, double& value) {
  if (token.empty()) return false;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

bool ParseIndex(std::string_view token, uint32_t& value) {
  if (token.empty()) return false;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

absl::Status FieldError(const std::string& field, const std::string& what, std::string_view got) {
  return absl::InvalidArgumentError(
      absl::StrCat("field ", field, ": expected ", what, ", got \"", std::string(got), "\""));
}

// Parses the fields of one data line (4 or 5 of them) into `o`.
absl::Status ParseFields(const std::vector<std::string_view>& f, CellObservation& o) {
  const bool has_z = f.size() == 5;
  if (!ParseDouble(f[0], o.t) || !std::isfinite(o.t) || std::fabs(o.t) > model::kMaxAbsTime) {
    return FieldError("time", "a finite time in seconds within ±1e13", f[0]);
  }
  if (!ParseIndex(f[1], o.x)) return FieldError("x", "a cell index (an integer in [0, 4294967295])", f[1]);
  if (!ParseIndex(f[2], o.y)) return FieldError("y", "a cell index (an integer in [0, 4294967295])", f[2]);
  o.z = 0;
  if (has_z && !ParseIndex(f[3], o.z)) return FieldError("z", "a cell index (an integer in [0, 4294967295])", f[3]);
  double s;
  const std::string_view state = f[has_z ? 4 : 3];
  // Checked in double: a value just above 1 would otherwise round into range as a float.
  if (!ParseDouble(state, s) || !(s >= 0.0 && s <= 1.0)) return FieldError("state", "a number in [0, 1]", state);
  o.s = static_cast<float>(s);
  return absl::OkStatus();
}

bool IsHeader(const std::vector<std::string_view>& f) {
  return (f.size() == 4 && f[0] == "time" && f[1] == "x" && f[2] == "y" && f[3] == "state") ||
         (f.size() == 5 && f[0] == "time" && f[1] == "x" && f[2] == "y" && f[3] == "z" && f[4] == "state");
}

}  // namespace

absl::StatusOr<std::vector<CellObservation>> ReadGridCsv(std::istream& in, const std::string& name) {
  std::vector<CellObservation> observations;
  size_t columns = 0;  // fixed by the header or the first data line
  bool first_line = true;
  std::string raw;
  for (int number = 1; std::getline(in, raw); ++number) {
    const std::string_view line = Trim(raw);
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> fields = SplitCommas(line);
    const auto error = [&](const absl::Status& status) {
      return absl::InvalidArgumentError(absl::StrCat(name, ":", number, ": ", status.message()));
    };
    if (first_line) {
      first_line = false;
      if (IsHeader(fields)) {
        columns = fields.size();
        continue;
      }
      if (!fields.empty() && fields[0] == "time") {
        return error(absl::InvalidArgumentError(
            absl::StrCat("the header must be time,x,y,state or time,x,y,z,state, got \"", std::string(line), "\"")));
      }
    }
    if (fields.size() != 4 && fields.size() != 5) {
      return error(absl::InvalidArgumentError(
          absl::StrCat("expected 4 fields time,x,y,state or 5 fields time,x,y,z,state, got ", fields.size())));
    }
    if (columns == 0) columns = fields.size();
    if (fields.size() != columns) {
      return error(absl::InvalidArgumentError(
          absl::StrCat("expected ", columns, " fields as on the lines before, got ", fields.size())));
    }
    CellObservation o;
    if (absl::Status status = ParseFields(fields, o); !status.ok()) return error(status);
    observations.push_back(o);
  }
  if (in.bad()) return absl::DataLossError(absl::StrCat(name, ": read error"));
  if (observations.empty()) return absl::InvalidArgumentError(absl::StrCat(name, ": no observations"));
  return observations;
}

absl::StatusOr<std::vector<CellObservation>> ReadGridCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open: ", std::strerror(errno)));
  return ReadGridCsv(in, path);
}

}  // namespace fremen::formats
