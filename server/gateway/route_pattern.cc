#include "server/gateway/route_pattern.h"

#include <httplib.h>

#include "absl/strings/match.h"
#include "absl/strings/str_split.h"

namespace fremen::server {

namespace {

// '/'-separated parts of `path` after its leading '/', ignoring '/' inside braces.
std::vector<std::string> SplitOutsideBraces(absl::string_view path) {
  std::vector<std::string> parts;
  std::string current;
  int depth = 0;
  for (char c : path.substr(1)) {
    if (c == '{') ++depth;
    if (c == '}') --depth;
    if (c == '/' && depth == 0) {
      parts.push_back(std::move(current));
      current.clear();
    } else {
      current += c;
    }
  }
  parts.push_back(std::move(current));
  return parts;
}

}  // namespace

RoutePattern::RoutePattern(absl::string_view pattern) : text_(pattern) {
  std::vector<std::string> parts = SplitOutsideBraces(pattern);
  // The verb is what follows the last ':' outside braces in the last part.
  std::string& last = parts.back();
  const size_t close = last.rfind('}');
  const size_t colon = last.rfind(':');
  if (colon != std::string::npos && (close == std::string::npos || colon > close)) {
    verb_ = last.substr(colon);
    last.resize(colon);
  }
  for (const std::string& part : parts) {
    if (!absl::StartsWith(part, "{")) {
      segments_.push_back({part, "", "", false});
      continue;
    }
    const std::string inside = part.substr(1, part.size() - 2);
    const size_t equals = inside.find('=');
    if (equals == std::string::npos) {
      segments_.push_back({"", inside, "", false});
      continue;
    }
    // {var=lit/.../*}: the literals, then the variable's own segment.
    const std::string variable = inside.substr(0, equals);
    std::vector<std::string> inner = absl::StrSplit(inside.substr(equals + 1), '/');
    std::string prefix;
    for (size_t i = 0; i + 1 < inner.size(); ++i) {
      segments_.push_back({inner[i], "", "", true});
      prefix += inner[i] + "/";
    }
    segments_.push_back({"", variable, prefix, false});
  }
}

std::optional<PathVariables> RoutePattern::Match(absl::string_view raw_path) const {
  if (!absl::StartsWith(raw_path, "/")) return std::nullopt;
  if (!verb_.empty()) {
    if (!absl::EndsWith(raw_path, verb_)) return std::nullopt;
    raw_path.remove_suffix(verb_.size());
  }
  std::vector<absl::string_view> parts = absl::StrSplit(raw_path.substr(1), '/');
  if (parts.size() != segments_.size()) return std::nullopt;
  PathVariables variables;
  for (size_t i = 0; i < parts.size(); ++i) {
    const Segment& segment = segments_[i];
    if (segment.variable.empty()) {
      if (parts[i] != segment.literal) return std::nullopt;
      continue;
    }
    if (parts[i].empty() || absl::StrContains(parts[i], ':')) return std::nullopt;
    variables[segment.variable] = segment.captured_prefix + httplib::detail::decode_url(std::string(parts[i]), false);
  }
  return variables;
}

}  // namespace fremen::server
