// Map YAML reading and writing (see map_yaml.h).
#include "client/formats/map_yaml.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace fremen::formats {

namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// A value without a trailing comment and without its quotes.
std::string_view Unquote(std::string_view value) {
  if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') && value.back() == value.front()) {
    return value.substr(1, value.size() - 2);
  }
  return value;
}

std::string_view StripComment(std::string_view line) {
  // A '#' starts a comment outside quotes (map names seldom hold one; quotes are honoured anyway).
  char quote = 0;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
      return line.substr(0, i);
    }
  }
  return line;
}

bool ParseNumber(std::string_view text, double& value) {
  text = Trim(text);
  if (text.empty()) return false;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && ptr == text.data() + text.size() && std::isfinite(value);
}

// The shortest text that reads back as exactly `value`: the origin must place the cells exactly
// where the map has them, and 0.65 should stay "0.65".
std::string Shortest(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, ec == std::errc() ? end : buffer);
}

struct Entry {
  std::string value;
  int line = 0;
};

class Parser {
 public:
  explicit Parser(const std::string& name) : name_(name) {}

  absl::Status Error(const std::string& key, const std::string& what) const {
    const auto it = entries_.find(key);
    const std::string where = it == entries_.end() ? name_ : absl::StrCat(name_, ":", it->second.line);
    return absl::InvalidArgumentError(absl::StrCat(where, ": ", key, " ", what));
  }

  absl::Status Load(const std::string& text) {
    std::istringstream in(text);
    std::string raw;
    for (int number = 1; std::getline(in, raw); ++number) {
      const std::string_view line = Trim(StripComment(raw));
      if (line.empty() || line == "---") continue;
      const size_t colon = line.find(':');
      if (colon == std::string_view::npos) {
        return absl::InvalidArgumentError(
            absl::StrCat(name_, ":", number, ": expected `key: value`, got \"", std::string(line), "\""));
      }
      const std::string key(Trim(line.substr(0, colon)));
      if (entries_.count(key) != 0) {
        return absl::InvalidArgumentError(absl::StrCat(name_, ":", number, ": ", key, " is given twice"));
      }
      entries_[key] = {std::string(Trim(line.substr(colon + 1))), number};
    }
    return absl::OkStatus();
  }

  const Entry* Find(const std::string& key) const {
    const auto it = entries_.find(key);
    return it == entries_.end() ? nullptr : &it->second;
  }

  absl::Status Number(const std::string& key, double& value, bool required) const {
    const Entry* entry = Find(key);
    if (entry == nullptr) return required ? Error(key, "is missing (a number is required)") : absl::OkStatus();
    if (!ParseNumber(entry->value, value))
      return Error(key, absl::StrCat("must be a number, got \"", entry->value, "\""));
    return absl::OkStatus();
  }

 private:
  const std::string& name_;
  std::map<std::string, Entry> entries_;
};

}  // namespace

absl::StatusOr<MapMetadata> ParseMapYaml(const std::string& text, const std::string& name) {
  Parser parser(name);
  if (absl::Status status = parser.Load(text); !status.ok()) return status;
  MapMetadata m;

  const Entry* image = parser.Find("image");
  if (image == nullptr || Unquote(image->value).empty()) {
    return parser.Error("image", "is missing (the name of the PGM file is required)");
  }
  m.image = std::string(Unquote(image->value));

  if (absl::Status s = parser.Number("resolution", m.resolution, true); !s.ok()) return s;
  if (!(m.resolution > 0))
    return parser.Error("resolution", absl::StrCat("must be > 0 metres per pixel, got ", m.resolution));

  const Entry* origin = parser.Find("origin");
  if (origin == nullptr) return parser.Error("origin", "is missing ([x, y, yaw] is required)");
  {
    std::string_view seq = Trim(origin->value);
    if (seq.size() < 2 || seq.front() != '[' || seq.back() != ']') {
      return parser.Error("origin", absl::StrCat("must be [x, y, yaw], got \"", origin->value, "\""));
    }
    seq = seq.substr(1, seq.size() - 2);
    std::vector<double> values;
    while (!seq.empty()) {
      const size_t comma = seq.find(',');
      double v;
      if (!ParseNumber(seq.substr(0, comma), v)) {
        return parser.Error("origin", absl::StrCat("must be [x, y, yaw] of numbers, got \"", origin->value, "\""));
      }
      values.push_back(v);
      if (comma == std::string_view::npos) break;
      seq.remove_prefix(comma + 1);
    }
    if (values.size() != 3) {
      return parser.Error("origin", absl::StrCat("must have 3 numbers [x, y, yaw], got ", values.size()));
    }
    m.origin_x = values[0];
    m.origin_y = values[1];
    m.origin_yaw = values[2];
  }

  if (const Entry* negate = parser.Find("negate"); negate != nullptr) {
    const std::string_view v = Unquote(negate->value);
    if (v == "0" || v == "false" || v == "False") {
      m.negate = false;
    } else if (v == "1" || v == "true" || v == "True") {
      m.negate = true;
    } else {
      return parser.Error("negate", absl::StrCat("must be 0 or 1, got \"", negate->value, "\""));
    }
  }
  if (absl::Status s = parser.Number("occupied_thresh", m.occupied_thresh, false); !s.ok()) return s;
  if (absl::Status s = parser.Number("free_thresh", m.free_thresh, false); !s.ok()) return s;
  if (!(m.occupied_thresh <= 1.0)) return parser.Error("occupied_thresh", "must be at most 1");
  if (!(m.free_thresh >= 0.0)) return parser.Error("free_thresh", "must be at least 0");
  if (!(m.free_thresh < m.occupied_thresh)) {
    return parser.Error("free_thresh",
                        absl::StrCat("must be below occupied_thresh (", m.occupied_thresh, "), got ", m.free_thresh));
  }
  if (const Entry* mode = parser.Find("mode"); mode != nullptr) {
    const std::string_view v = Unquote(mode->value);
    if (v == "trinary") {
      m.mode = MapMode::kTrinary;
    } else if (v == "scale") {
      m.mode = MapMode::kScale;
    } else {
      return parser.Error("mode",
                          absl::StrCat("must be trinary or scale (raw is not supported), got \"", mode->value, "\""));
    }
  }
  return m;
}

absl::StatusOr<MapMetadata> ReadMapYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open: ", std::strerror(errno)));
  std::ostringstream text;
  text << in.rdbuf();
  return ParseMapYaml(text.str(), path);
}

std::string ResolveImagePath(const std::string& yaml_path, const MapMetadata& metadata) {
  const std::filesystem::path image(metadata.image);
  if (image.is_absolute()) return image.string();
  return (std::filesystem::path(yaml_path).parent_path() / image).string();
}

absl::Status WriteMapYaml(const std::string& path, const MapMetadata& m) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) return absl::PermissionDeniedError(absl::StrCat(path, ": cannot create: ", std::strerror(errno)));
  out << "image: " << m.image << "\n"
      << "mode: " << (m.mode == MapMode::kScale ? "scale" : "trinary") << "\n"
      << "resolution: " << Shortest(m.resolution) << "\n"
      << "origin: [" << Shortest(m.origin_x) << ", " << Shortest(m.origin_y) << ", " << Shortest(m.origin_yaw) << "]\n"
      << "negate: " << (m.negate ? 1 : 0) << "\n"
      << "occupied_thresh: " << Shortest(m.occupied_thresh) << "\n"
      << "free_thresh: " << Shortest(m.free_thresh) << "\n";
  out.close();
  if (!out) return absl::DataLossError(absl::StrCat(path, ": write error"));
  return absl::OkStatus();
}

}  // namespace fremen::formats
