#include "server/dashboard/dashboard_routes.h"

#include <string>
#include <string_view>

#include "absl/strings/ascii.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "absl/strings/strip.h"
#include "server/dashboard/embedded_files.h"

namespace fremen::server {

namespace {

// Whether an If-None-Match header names `etag`: "*", or one of a comma-separated list, weak
// (W/"…") or strong — RFC 9110's weak comparison, which is what a GET's revalidation uses.
// (Debian's Abseil has its own string_view, not std's.)
bool Matches(absl::string_view if_none_match, std::string_view etag) {
  for (absl::string_view tag : absl::StrSplit(if_none_match, ',')) {
    tag = absl::StripAsciiWhitespace(tag);
    absl::ConsumePrefix(&tag, "W/");
    if (tag == "*" || std::string_view(tag.data(), tag.size()) == etag) return true;
  }
  return false;
}

void Serve(const EmbeddedFile& file, const httplib::Request& request, httplib::Response& response) {
  response.set_header("ETag", std::string(file.etag));
  response.set_header("Cache-Control", "no-cache");
  response.set_header("X-Content-Type-Options", "nosniff");
  // The pages load only their own files and call only this origin; no other site may frame them
  // (a framed "run the update now" could be clicked by a user who does not see it).
  response.set_header("Content-Security-Policy", "default-src 'self'; img-src 'self' data:; frame-ancestors 'none'");
  if (Matches(request.get_header_value("If-None-Match"), file.etag)) {
    response.status = 304;
    return;
  }
  response.set_content(file.bytes.data(), file.bytes.size(), std::string(file.content_type));
}

}  // namespace

void AddDashboardRoutes(httplib::Server& server) {
  // index.html and favicon.svg are always embedded (server/CMakeLists.txt lists them).
  server.Get("/", [](const httplib::Request& request, httplib::Response& response) {
    Serve(*FindEmbeddedFile("index.html"), request, response);
  });
  // Browsers ask for /favicon.ico on their own (for pages that are not HTML, too).
  server.Get("/favicon.ico", [](const httplib::Request& request, httplib::Response& response) {
    Serve(*FindEmbeddedFile("favicon.svg"), request, response);
  });
  server.Get(R"(/static/([^/]+))", [](const httplib::Request& request, httplib::Response& response) {
    const std::string name = request.matches[1];
    const EmbeddedFile* file = FindEmbeddedFile(name);
    if (file == nullptr) {
      response.status = 404;
      response.set_content("no such dashboard file: " + name + "\n", "text/plain");
      return;
    }
    Serve(*file, request, response);
  });
}

}  // namespace fremen::server
