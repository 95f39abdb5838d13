// How the HTTP port says that a call failed, the grpc-gateway way: the HTTP status of a gRPC code
// and a google.rpc.Status-shaped JSON body, {"code": 3, "message": "...", "details": []}, so that
// an HTTP client reads the same code and message a gRPC client gets.
// Pure functions; thread-safe.
#pragma once

#include <httplib.h>

#include <string>

#include "absl/status/status.h"

namespace fremen::server {

// INVALID_ARGUMENT, FAILED_PRECONDITION, OUT_OF_RANGE 400; UNAUTHENTICATED 401; PERMISSION_DENIED
// 403; NOT_FOUND 404; ALREADY_EXISTS, ABORTED 409; RESOURCE_EXHAUSTED 429; CANCELLED 499;
// UNIMPLEMENTED 501; UNAVAILABLE 503; DEADLINE_EXCEEDED 504; OK 200; the others 500.
int HttpStatusOf(absl::StatusCode code);

// The JSON body of a failed `status` (code as its number).
std::string StatusBody(const absl::Status& status);

// Answers `response` with `status`: its HTTP status, StatusBody as application/json, and a
// WWW-Authenticate challenge on 401. REQUIRES: !status.ok().
void SetErrorResponse(const absl::Status& status, httplib::Response& response);

}  // namespace fremen::server
