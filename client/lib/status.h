// The one place where the client turns a grpc::Status into an absl::Status: the same canonical code
// (gRPC's and absl's codes are the same numbers) and the daemon's message, which names the field
// at fault and what to do.
// Thread-safety: pure functions.
#pragma once

#include <grpcpp/support/status.h>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace fremen::client {

// `address` is named in the message of errors the daemon did not write itself (UNAVAILABLE,
// DEADLINE_EXCEEDED from the client's side), so that the user knows which daemon was meant.
absl::Status FromGrpcStatus(const grpc::Status& status, absl::string_view address = "");

// Whether `code` may be retried on an idempotent call: the daemon or the link is (briefly) gone.
inline bool IsRetryable(absl::StatusCode code) { return code == absl::StatusCode::kUnavailable; }

}  // namespace fremen::client
