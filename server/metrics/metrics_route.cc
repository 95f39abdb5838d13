#include "server/metrics/metrics_route.h"

#include <optional>
#include <string>

namespace fremen::server {

namespace {

// The HTTP status of an authorization refusal.
int RefusalStatus(const absl::Status& status) {
  return status.code() == absl::StatusCode::kPermissionDenied ? 403 : 401;
}

}  // namespace

void AddMetricsRoute(httplib::Server& server, const Metrics* metrics, const Authenticator* auth) {
  server.Get("/metrics", [metrics, auth](const httplib::Request& request, httplib::Response& response) {
    const std::string header = request.get_header_value("Authorization");
    std::optional<absl::string_view> authorization;
    if (request.has_header("Authorization")) authorization = header;
    if (absl::Status denied = auth->AuthorizeHeader(authorization, Access::kRead, "/metrics"); !denied.ok()) {
      response.status = RefusalStatus(denied);
      if (response.status == 401) response.set_header("WWW-Authenticate", "Bearer");
      response.set_content(std::string(denied.message()) + "\n", "text/plain");
      return;
    }
    response.set_content(metrics->Scrape(), "text/plain; version=0.0.4; charset=utf-8");
  });
}

}  // namespace fremen::server
