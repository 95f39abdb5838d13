#include "server/http/health_routes.h"

#include <utility>

namespace fremen::server {

void AddHealthRoutes(httplib::Server& server, ReadinessProbe not_ready_because) {
  server.Get("/healthz", [](const httplib::Request&, httplib::Response& response) {
    response.set_content("ok\n", "text/plain");
  });
  server.Get("/readyz", [probe = std::move(not_ready_because)](const httplib::Request&, httplib::Response& response) {
    const std::string reason = probe();
    if (reason.empty()) {
      response.set_content("ready\n", "text/plain");
      return;
    }
    response.status = 503;
    response.set_content("not ready: " + reason + "\n", "text/plain");
  });
}

}  // namespace fremen::server
