// The fields of a request message set from an HTTP request's query parameters, by (dotted) proto
// field name, through protobuf reflection (grpc-gateway's convention): `?lo.x=0&hi.x=64&time=1.7e9
// &output=REGION_OUTPUT_UINT8&times=1&times=2`. Scalars of every type (64-bit integers too), bools
// (true/false/1/0), enums by name or number, nested messages by their dotted path (oneof members
// too), repeated fields by repeating the parameter. Errors are INVALID_ARGUMENT naming the
// parameter: "unknown query parameter: foo", "query parameter lo.x: not an integer: abc".
// Pure functions; thread-safe.
#pragma once

#include <google/protobuf/message.h>

#include <map>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace fremen::server {

// Sets (or, for a repeated field, appends) the field named by `dotted` to `value`.
absl::Status SetField(absl::string_view dotted, absl::string_view value, google::protobuf::Message& message);

// SetField for every parameter, in order (a repeated field keeps the parameters' order). A
// singular field given twice is an error.
absl::Status SetFieldsFromQuery(const std::multimap<std::string, std::string>& params,
                                google::protobuf::Message& message);

}  // namespace fremen::server
