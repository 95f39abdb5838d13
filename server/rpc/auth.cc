#include "server/rpc/auth.h"

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"

namespace fremen::server {

namespace {

constexpr absl::string_view kScheme = "bearer ";

// Equal in time that depends only on the lengths, not on where the strings first differ.
bool ConstantTimeEquals(absl::string_view a, absl::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

}  // namespace

absl::Status Authenticator::Authorize(const grpc::ServerContextBase& context, Access needed,
                                      absl::string_view method) const {
  if (!enabled()) return absl::OkStatus();
  const auto& metadata = context.client_metadata();
  const auto it = metadata.find("authorization");
  std::optional<absl::string_view> header;
  if (it != metadata.end()) header = absl::string_view(it->second.data(), it->second.size());
  return AuthorizeHeader(header, needed, method);
}

absl::Status Authenticator::AuthorizeHeader(std::optional<absl::string_view> authorization, Access needed,
                                            absl::string_view method) const {
  if (!enabled()) return absl::OkStatus();
  if (!authorization) {
    return absl::UnauthenticatedError(
        absl::StrCat(method, " needs a token: send the metadata \"authorization: Bearer <token>\""));
  }
  if (authorization->size() <= kScheme.size() ||
      !absl::EqualsIgnoreCase(authorization->substr(0, kScheme.size()), kScheme)) {
    return absl::UnauthenticatedError("the authorization metadata must be \"Bearer <token>\"");
  }
  const absl::string_view token = absl::StripAsciiWhitespace(authorization->substr(kScheme.size()));
  const TokenGrant* match = nullptr;
  for (const TokenGrant& grant : tokens_) {
    if (ConstantTimeEquals(grant.token, token)) match = &grant;
  }
  if (match == nullptr) return absl::UnauthenticatedError("the bearer token is not valid");
  if (needed == Access::kWrite && match->access != Access::kWrite) {
    return absl::PermissionDeniedError(absl::StrCat(method, " needs a write token; this token may only read"));
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
