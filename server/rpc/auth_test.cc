#include "server/rpc/auth.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

const Authenticator kWithTokens({{"reader-secret", Access::kRead}, {"writer-secret", Access::kWrite}});

TEST(AuthenticatorTest, WithoutTokensEverythingIsAllowed) {
  const Authenticator open({});
  EXPECT_FALSE(open.enabled());
  EXPECT_TRUE(open.AuthorizeHeader(std::nullopt, Access::kWrite, "CreateMap").ok());
  EXPECT_TRUE(open.AuthorizeHeader("Bearer anything", Access::kWrite, "CreateMap").ok());
}

TEST(AuthenticatorTest, MissingOrMalformedHeaderIsUnauthenticated) {
  const absl::Status missing = kWithTokens.AuthorizeHeader(std::nullopt, Access::kRead, "GetMap");
  EXPECT_EQ(missing.code(), absl::StatusCode::kUnauthenticated);
  EXPECT_THAT(missing.message(), HasSubstr("GetMap needs a token"));
  EXPECT_EQ(kWithTokens.AuthorizeHeader("Basic cmVhZGVy", Access::kRead, "GetMap").code(),
            absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(kWithTokens.AuthorizeHeader("Bearer ", Access::kRead, "GetMap").code(),
            absl::StatusCode::kUnauthenticated);
}

TEST(AuthenticatorTest, UnknownTokenIsUnauthenticated) {
  EXPECT_EQ(kWithTokens.AuthorizeHeader("Bearer reader-secreT", Access::kRead, "GetMap").code(),
            absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(kWithTokens.AuthorizeHeader("Bearer reader", Access::kRead, "GetMap").code(),
            absl::StatusCode::kUnauthenticated);
}

TEST(AuthenticatorTest, RolesDecideWhatATokenMayDo) {
  EXPECT_TRUE(kWithTokens.AuthorizeHeader("Bearer reader-secret", Access::kRead, "GetMap").ok());
  EXPECT_TRUE(kWithTokens.AuthorizeHeader("bearer writer-secret", Access::kRead, "GetMap").ok());
  EXPECT_TRUE(kWithTokens.AuthorizeHeader("Bearer writer-secret", Access::kWrite, "CreateMap").ok());
  const absl::Status denied = kWithTokens.AuthorizeHeader("Bearer reader-secret", Access::kWrite, "CreateMap");
  EXPECT_EQ(denied.code(), absl::StatusCode::kPermissionDenied);
  EXPECT_THAT(denied.message(), HasSubstr("CreateMap needs a write token"));
}

}  // namespace
}  // namespace fremen::server
