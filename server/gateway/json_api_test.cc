// The dispatcher alone, on a real HTTP listener: before the daemon's channel exists every route is
// 503 UNAVAILABLE; unknown paths and methods answer without any channel. The routes themselves are
// tested against a real fremend in tests/http_api_test.cc.
#include "server/gateway/json_api.h"

#include <set>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/http/http_server.h"

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

TEST(JsonApiTest, TheTableHasEveryRouteOnce) {
  std::set<std::pair<std::string, std::string>> seen;
  for (const JsonRoute& route : JsonApiRoutes()) {
    EXPECT_TRUE(seen.emplace(route.method, route.pattern.text()).second) << route.method << " " << route.pattern.text();
    EXPECT_TRUE(route.handler != nullptr) << route.pattern.text();
  }
  EXPECT_EQ(seen.size(), 25u);  // docs/http.md's table
}

TEST(JsonApiTest, AnswersUnavailableUntilThereIsAChannel) {
  HttpServer http(HttpServer::Options{"127.0.0.1:0", "", "", ""});
  AddJsonApi(http.routes(), [] { return std::shared_ptr<grpc::Channel>(); });
  ASSERT_TRUE(http.Start().ok());
  const size_t colon = http.address().rfind(':');
  httplib::Client client(http.address().substr(0, colon), std::stoi(http.address().substr(colon + 1)));

  const httplib::Result maps = client.Get("/v1/maps");
  ASSERT_TRUE(maps);
  EXPECT_EQ(maps->status, 503);
  EXPECT_THAT(maps->body, HasSubstr("\"code\":14"));

  const httplib::Result unknown = client.Get("/v1/nothing");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 404);
  const httplib::Result wrong = client.Delete("/v1/operations");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 405);
  EXPECT_EQ(wrong->get_header_value("Allow"), "GET");
  // Outside /v1: not the JSON API's (httplib's own 404).
  const httplib::Result other = client.Get("/elsewhere");
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 404);
  EXPECT_THAT(other->body, ::testing::Not(HasSubstr("\"code\"")));
  http.Stop();
}

}  // namespace
}  // namespace fremen::server
