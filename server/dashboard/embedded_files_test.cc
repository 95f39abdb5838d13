// The embedded dashboard: every file of server/dashboard/web/ is in the binary with its bytes,
// content type and ETag; Chart.js too; unknown names are not found.
#include "server/dashboard/embedded_files.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace fremen::server {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

const std::filesystem::path kWebDir = std::filesystem::path(FREMEN_SOURCE_DIR) / "server/dashboard/web";

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

TEST(EmbeddedFilesTest, EveryWebFileIsEmbeddedWithItsBytes) {
  size_t web_files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kWebDir)) {
    const std::string name = entry.path().filename().string();
    const EmbeddedFile* file = FindEmbeddedFile(name);
    ASSERT_NE(file, nullptr) << name << " is in web/ but not embedded: add it to server/CMakeLists.txt";
    EXPECT_EQ(file->bytes, ReadFile(entry.path())) << name;
    ++web_files;
  }
  EXPECT_GE(web_files, 8u);
  // web/ plus Chart.js, nothing else.
  EXPECT_EQ(EmbeddedFiles().size(), web_files + 1);
}

TEST(EmbeddedFilesTest, ChartJsIsDebiansBuild) {
  const EmbeddedFile* chart = FindEmbeddedFile("chart.min.js");
  ASSERT_NE(chart, nullptr);
  EXPECT_EQ(chart->bytes, ReadFile("/usr/share/javascript/chart.js/chart.min.js"));
  EXPECT_THAT(std::string(chart->bytes.substr(0, 200)), HasSubstr("Chart.js"));
}

TEST(EmbeddedFilesTest, ContentTypesFollowTheExtension) {
  EXPECT_EQ(FindEmbeddedFile("index.html")->content_type, "text/html; charset=utf-8");
  EXPECT_EQ(FindEmbeddedFile("style.css")->content_type, "text/css; charset=utf-8");
  EXPECT_EQ(FindEmbeddedFile("app.js")->content_type, "text/javascript; charset=utf-8");
  EXPECT_EQ(FindEmbeddedFile("chart.min.js")->content_type, "text/javascript; charset=utf-8");
  EXPECT_EQ(FindEmbeddedFile("favicon.svg")->content_type, "image/svg+xml");
}

TEST(EmbeddedFilesTest, EtagsAreQuotedSha256sAndDiffer) {
  std::set<std::string_view> etags;
  for (const EmbeddedFile& file : EmbeddedFiles()) {
    EXPECT_THAT(std::string(file.etag), StartsWith("\"")) << file.path;
    EXPECT_EQ(file.etag.size(), 64u + 2) << file.path;
    EXPECT_EQ(file.etag.back(), '"') << file.path;
    etags.insert(file.etag);
  }
  EXPECT_EQ(etags.size(), EmbeddedFiles().size());
  // The digest is the file's own, as coreutils' sha256sum computes it.
  const std::string index = (kWebDir / "index.html").string();
  FILE* pipe = popen(("sha256sum '" + index + "'").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char digest[65] = {};
  ASSERT_EQ(fread(digest, 1, 64, pipe), 64u);
  pclose(pipe);
  EXPECT_EQ(FindEmbeddedFile("index.html")->etag, "\"" + std::string(digest) + "\"");
}

TEST(EmbeddedFilesTest, UnknownNamesAreNotFound) {
  EXPECT_EQ(FindEmbeddedFile("no-such.js"), nullptr);
  EXPECT_EQ(FindEmbeddedFile(""), nullptr);
  EXPECT_EQ(FindEmbeddedFile("web/app.js"), nullptr);
  EXPECT_EQ(FindEmbeddedFile("../app.js"), nullptr);
}

}  // namespace
}  // namespace fremen::server
