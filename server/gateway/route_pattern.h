// A route of the JSON API as grpc-gateway spells it: "/v1/maps/{map}/{name=operations/*}:cancel".
// Segments are literals, `{var}` (one whole segment), `{var=lit/*}` (literal segments then one
// segment, captured together as "lit/value": an operation's name is "operations/update-lab-3"),
// and the last segment may end in a custom verb (":cancel", after a variable or a literal).
//
// Match takes the raw path of the request (before URL decoding, so that an encoded "/" stays
// inside its segment) and URL-decodes what it captures. A variable's raw segment never holds ':'
// (map names never do), so that "/v1/maps/lab:predict" is the :predict route and not GET
// /v1/maps/{map} of a map named "lab:predict". Pure values; thread-safe once built.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/string_view.h"

namespace fremen::server {

// Variable name → its URL-decoded value.
using PathVariables = std::map<std::string, std::string>;

class RoutePattern {
 public:
  // REQUIRES: a well-formed pattern starting with '/' (the route table's own constants).
  explicit RoutePattern(absl::string_view pattern);

  // The variables of `raw_path` when it matches; nullopt when it does not.
  std::optional<PathVariables> Match(absl::string_view raw_path) const;

  const std::string& text() const { return text_; }

 private:
  struct Segment {
    std::string literal;  // the segment itself when `variable` is empty
    std::string variable;
    std::string captured_prefix;  // {var=lit/*}: "lit/" put before the value
    bool part_of_variable = false;  // a literal that belongs to the next segment's {var=lit/*}
  };

  std::string text_;
  std::vector<Segment> segments_;
  std::string verb_;  // ":cancel", or ""
};

}  // namespace fremen::server
