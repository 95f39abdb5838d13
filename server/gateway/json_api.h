// fremend's JSON API on the HTTP port (docs/http.md, "JSON API"): /v1/... routes that mirror the
// gRPC services the grpc-gateway way. Each route is one row of a table — method, path pattern
// (route_pattern.h), and a forwarding of the request to one gRPC method over the daemon's
// in-process channel (grpc_forward.h) — and one dispatcher per HTTP method serves them all:
//   - GET query parameters set request fields by dotted proto name (request_fields.h); POST
//     bodies are the whole request message in protobuf's JSON mapping (query parameters may add
//     fields); the path's variables ({map}, {name}, {writer_id}) set their fields last.
//   - Answers are the response message in protobuf's JSON mapping (lowerCamelCase, every field
//     printed, 64-bit integers as strings, enums by name, bytes as base64); region.png is a PNG.
//   - Errors carry the gRPC call's code and message: the HTTP status and google.rpc.Status body
//     of server/http/http_status.h. An unknown /v1 path is 404 NOT_FOUND; a known path with
//     another method 405 (UNIMPLEMENTED) with an Allow header.
// Thread-safety: the handlers run on httplib's threads; `channel` must be callable from them.
#pragma once

#include <grpcpp/grpcpp.h>
#include <httplib.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "server/gateway/route_pattern.h"

namespace fremen::server {

// The channel to the daemon's gRPC services; nullptr while there is none (answered 503 UNAVAILABLE).
using ChannelSource = std::function<std::shared_ptr<grpc::Channel>()>;

struct JsonRoute {
  using Handler = std::function<void(const std::shared_ptr<grpc::Channel>& channel, const httplib::Request& http,
                                     const PathVariables& variables, httplib::Response& response)>;
  std::string method;  // "GET", "POST", "DELETE"
  RoutePattern pattern;
  Handler handler;
};

// Every route, in the order docs/http.md lists them.
const std::vector<JsonRoute>& JsonApiRoutes();

// Registers the dispatchers of /v1 and /v1/... for GET, POST, DELETE, PUT and PATCH.
void AddJsonApi(httplib::Server& server, ChannelSource channel);

}  // namespace fremen::server
