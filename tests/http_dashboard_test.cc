// The web dashboard on fremend's HTTP port end to end (docs/http.md, "Dashboard"): a real daemon
// serves the embedded files at / and /static/<name>, revalidated by ETag, with no token needed
// even when tokens are configured (the files hold no data; the pages' API calls carry the token).
#include <httplib.h>

#include <fstream>
#include <sstream>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/fremend_fixture.h"
#include "tests/http_client.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string SourceFile(const std::string& path) {
  std::ifstream in(std::string(FREMEN_SOURCE_DIR) + "/" + path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

class HttpDashboardTest : public DaemonTest {
 protected:
  httplib::Result Get(const std::string& path, const httplib::Headers& headers = {}) {
    httplib::Client client = HttpClientFor(daemon_->http_address());
    httplib::Result result = client.Get(path.c_str(), headers);
    EXPECT_TRUE(result) << path << ": " << httplib::to_string(result.error());
    return result;
  }
};

TEST_F(HttpDashboardTest, TheRootServesTheIndexPage) {
  const httplib::Result index = Get("/");
  ASSERT_TRUE(index);
  EXPECT_EQ(index->status, 200);
  EXPECT_EQ(index->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_EQ(index->body, SourceFile("server/dashboard/web/index.html"));
  EXPECT_THAT(index->body, HasSubstr("/static/app.js"));
  EXPECT_THAT(index->body, HasSubstr("/static/chart.min.js"));
  EXPECT_EQ(index->get_header_value("Cache-Control"), "no-cache");
  EXPECT_THAT(index->get_header_value("ETag"), StartsWith("\""));
  EXPECT_THAT(index->get_header_value("Content-Security-Policy"), HasSubstr("default-src 'self'"));
  EXPECT_THAT(index->get_header_value("Content-Security-Policy"), HasSubstr("frame-ancestors 'none'"));
  EXPECT_EQ(index->get_header_value("X-Content-Type-Options"), "nosniff");
}

TEST_F(HttpDashboardTest, StaticFilesAreServedWithTheirTypes) {
  for (const std::string name : {"app.js", "api.js", "grid_view.js", "model_view.js", "style.css"}) {
    const httplib::Result file = Get("/static/" + name);
    ASSERT_TRUE(file);
    EXPECT_EQ(file->status, 200) << name;
    EXPECT_EQ(file->body, SourceFile("server/dashboard/web/" + name)) << name;
    EXPECT_EQ(file->get_header_value("Content-Type"),
              name.ends_with(".css") ? "text/css; charset=utf-8" : "text/javascript; charset=utf-8")
        << name;
  }
  // The icon browsers ask for by themselves.
  const httplib::Result icon = Get("/favicon.ico");
  ASSERT_TRUE(icon);
  EXPECT_EQ(icon->status, 200);
  EXPECT_EQ(icon->get_header_value("Content-Type"), "image/svg+xml");
  EXPECT_EQ(icon->body, SourceFile("server/dashboard/web/favicon.svg"));
  // Chart.js, Debian's build, from the binary.
  const httplib::Result chart = Get("/static/chart.min.js");
  ASSERT_TRUE(chart);
  EXPECT_EQ(chart->status, 200);
  EXPECT_GT(chart->body.size(), 100000u);
  EXPECT_THAT(chart->body.substr(0, 200), HasSubstr("Chart.js"));
}

TEST_F(HttpDashboardTest, AnUnchangedFileIsNotSentAgain) {
  const httplib::Result first = Get("/static/app.js");
  ASSERT_TRUE(first);
  const std::string etag = first->get_header_value("ETag");
  ASSERT_EQ(etag.size(), 66u) << etag;
  const httplib::Result again = Get("/static/app.js", {{"If-None-Match", etag}});
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 304);
  EXPECT_EQ(again->body, "");
  EXPECT_EQ(again->get_header_value("ETag"), etag);
  // A weak form of the same tag, and a list holding it, match too; another file's tag does not.
  EXPECT_EQ(Get("/static/app.js", {{"If-None-Match", "\"other\", W/" + etag}})->status, 304);
  const std::string css_etag = Get("/static/style.css")->get_header_value("ETag");
  EXPECT_NE(css_etag, etag);
  const httplib::Result changed = Get("/static/app.js", {{"If-None-Match", css_etag}});
  ASSERT_TRUE(changed);
  EXPECT_EQ(changed->status, 200);
  EXPECT_EQ(changed->body, first->body);
  // The index page revalidates the same way.
  const std::string index_etag = Get("/")->get_header_value("ETag");
  EXPECT_EQ(Get("/", {{"If-None-Match", index_etag}})->status, 304);
}

TEST_F(HttpDashboardTest, UnknownFilesAreNotFound) {
  const httplib::Result missing = Get("/static/no-such.js");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  EXPECT_THAT(missing->body, HasSubstr("no-such.js"));
  EXPECT_EQ(Get("/static/")->status, 404);
  EXPECT_EQ(Get("/static/../daemon.cc")->status, 404);
  EXPECT_EQ(Get("/static/web/app.js")->status, 404);
}

TEST_F(HttpDashboardTest, TheFilesNeedNoTokenEvenWithTokensConfigured) {
  StopDaemon();
  StartDaemon({"--tokens-file", dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n")});
  EXPECT_EQ(Get("/")->status, 200);
  EXPECT_EQ(Get("/static/app.js")->status, 200);
  EXPECT_EQ(Get("/static/chart.min.js")->status, 200);
  // What holds data still wants one.
  EXPECT_EQ(Get("/metrics")->status, 401);
}

}  // namespace
}  // namespace fremen::testing
