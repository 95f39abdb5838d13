// absl::Status → grpc::Status: the one place the server converts between the two. The codes map 1:1
// (both are the canonical codes of google.rpc.Code, pinned below), and the message is kept as is.
// Pure functions; thread-safe.
#pragma once

#include <grpcpp/support/status.h>

#include <string>

#include "absl/status/status.h"

namespace fremen::server {

#define FREMEN_SAME_CODE(absl_code, grpc_code) \
  static_assert(static_cast<int>(absl::StatusCode::absl_code) == static_cast<int>(grpc::StatusCode::grpc_code))
FREMEN_SAME_CODE(kOk, OK);
FREMEN_SAME_CODE(kCancelled, CANCELLED);
FREMEN_SAME_CODE(kUnknown, UNKNOWN);
FREMEN_SAME_CODE(kInvalidArgument, INVALID_ARGUMENT);
FREMEN_SAME_CODE(kDeadlineExceeded, DEADLINE_EXCEEDED);
FREMEN_SAME_CODE(kNotFound, NOT_FOUND);
FREMEN_SAME_CODE(kAlreadyExists, ALREADY_EXISTS);
FREMEN_SAME_CODE(kPermissionDenied, PERMISSION_DENIED);
FREMEN_SAME_CODE(kResourceExhausted, RESOURCE_EXHAUSTED);
FREMEN_SAME_CODE(kFailedPrecondition, FAILED_PRECONDITION);
FREMEN_SAME_CODE(kAborted, ABORTED);
FREMEN_SAME_CODE(kOutOfRange, OUT_OF_RANGE);
FREMEN_SAME_CODE(kUnimplemented, UNIMPLEMENTED);
FREMEN_SAME_CODE(kInternal, INTERNAL);
FREMEN_SAME_CODE(kUnavailable, UNAVAILABLE);
FREMEN_SAME_CODE(kDataLoss, DATA_LOSS);
FREMEN_SAME_CODE(kUnauthenticated, UNAUTHENTICATED);
#undef FREMEN_SAME_CODE

inline grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()), std::string(status.message()));
}

// The canonical name of a gRPC code ("INVALID_ARGUMENT"), for logs.
inline std::string StatusCodeName(grpc::StatusCode code) {
  return absl::StatusCodeToString(static_cast<absl::StatusCode>(code));
}

}  // namespace fremen::server
