// Bearer-token authorization of each call ("authorization: Bearer <token>" metadata) with two roles:
// a read token may call read methods, a write token every method. Without configured tokens every
// call is allowed (the default: the daemon listens on loopback).
//
// Missing, malformed or unknown token → UNAUTHENTICATED; a read token on a write method →
// PERMISSION_DENIED. Tokens are compared in constant time, against all of them, so that timing does
// not tell how much of a guess was right.
// Thread-safety: immutable after construction; Authorize may be called from any thread.
#pragma once

#include <grpcpp/server_context.h>

#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "server/daemon/config.h"

namespace fremen::server {

class Authenticator {
 public:
  explicit Authenticator(std::vector<TokenGrant> tokens) : tokens_(std::move(tokens)) {}

  bool enabled() const { return !tokens_.empty(); }

  // Checks the call's authorization metadata for `method` (named in the error).
  absl::Status Authorize(const grpc::ServerContextBase& context, Access needed, absl::string_view method) const;
  // The same on the header's value (nullopt: no header).
  absl::Status AuthorizeHeader(std::optional<absl::string_view> authorization, Access needed,
                               absl::string_view method) const;

 private:
  std::vector<TokenGrant> tokens_;
};

}  // namespace fremen::server
