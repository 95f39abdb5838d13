#include "server/metrics/metrics_route.h"

#include <optional>
#include <string>

#include "server/http/http_status.h"

namespace fremen::server {

void AddMetricsRoute(httplib::Server& server, const Metrics* metrics, const Authenticator* auth) {
  server.Get("/metrics", [metrics, auth](const httplib::Request& request, httplib::Response& response) {
    const std::string header = request.get_header_value("Authorization");
    std::optional<absl::string_view> authorization;
    if (request.has_header("Authorization")) authorization = header;
    if (absl::Status denied = auth->AuthorizeHeader(authorization, Access::kRead, "/metrics"); !denied.ok()) {
      SetErrorResponse(denied, response);  // as the JSON API's refusals
      return;
    }
    response.set_content(metrics->Scrape(), "text/plain; version=0.0.4; charset=utf-8");
  });
}

}  // namespace fremen::server
