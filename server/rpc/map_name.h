// Which map a call is about. Every request names its map in a field (`map`, or `map.name` for
// CreateMap), and clients also send it in the x-fremen-map header so that a proxy can route on it
// (docs/storage.md, "Maps across daemons"). The server accepts either; when both are set they
// must agree, so that a request a proxy routed by its header cannot act on another map.
// Pure functions; thread-safe.
#pragma once

#include <grpcpp/server_context.h>

#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace fremen::server {

inline constexpr char kMapHeader[] = "x-fremen-map";

// The map's name from the request's field (named `field` in errors) or the call's header.
// InvalidArgument when they differ or when neither is set.
absl::StatusOr<std::string> ResolveMapName(const grpc::ServerContextBase& context, absl::string_view request_map,
                                           absl::string_view field);
// The same on the header's value (nullopt: no header).
absl::StatusOr<std::string> ResolveMapName(std::optional<absl::string_view> header, absl::string_view request_map,
                                           absl::string_view field);

}  // namespace fremen::server
