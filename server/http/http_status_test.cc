#include "server/http/http_status.h"

#include <google/protobuf/util/json_util.h>

#include "fremen/v1/rpc_status.pb.h"

#include "gtest/gtest.h"

namespace fremen::server {
namespace {

TEST(HttpStatusTest, GrpcCodesMapAsGrpcGatewayMapsThem) {
  using C = absl::StatusCode;
  const std::vector<std::pair<C, int>> rows = {
      {C::kOk, 200},           {C::kInvalidArgument, 400},   {C::kFailedPrecondition, 400}, {C::kOutOfRange, 400},
      {C::kUnauthenticated, 401}, {C::kPermissionDenied, 403}, {C::kNotFound, 404},        {C::kAlreadyExists, 409},
      {C::kAborted, 409},      {C::kResourceExhausted, 429}, {C::kCancelled, 499},          {C::kUnimplemented, 501},
      {C::kUnavailable, 503},  {C::kDeadlineExceeded, 504},  {C::kInternal, 500},           {C::kDataLoss, 500},
      {C::kUnknown, 500},
  };
  for (const auto& [code, http] : rows) EXPECT_EQ(HttpStatusOf(code), http) << absl::StatusCodeToString(code);
}

TEST(HttpStatusTest, TheBodyIsAGoogleRpcStatus) {
  const std::string body = StatusBody(absl::NotFoundError("no map \"x\" (\\ and \" escaped)"));
  v1::RpcStatus parsed;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(body, &parsed).ok()) << body;
  EXPECT_EQ(parsed.code(), 5);
  EXPECT_EQ(parsed.message(), "no map \"x\" (\\ and \" escaped)");
  EXPECT_EQ(parsed.details_size(), 0);
  EXPECT_NE(body.find("\"details\":[]"), std::string::npos) << body;
  EXPECT_NE(body.find("\"code\":5"), std::string::npos) << body;  // an integer, as google.rpc.Status has it
}

TEST(HttpStatusTest, UnauthenticatedAnswersCarryABearerChallenge) {
  httplib::Response response;
  SetErrorResponse(absl::UnauthenticatedError("no token"), response);
  EXPECT_EQ(response.status, 401);
  EXPECT_EQ(response.get_header_value("WWW-Authenticate"), "Bearer");
  EXPECT_EQ(response.get_header_value("Content-Type"), "application/json");
  httplib::Response denied;
  SetErrorResponse(absl::PermissionDeniedError("read token"), denied);
  EXPECT_EQ(denied.status, 403);
  EXPECT_FALSE(denied.has_header("WWW-Authenticate"));
}

}  // namespace
}  // namespace fremen::server
