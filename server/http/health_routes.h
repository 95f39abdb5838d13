// The probes of load balancers and Kubernetes, on the HTTP port, without a token (a probe has
// none, and they tell nothing about the maps):
//   GET /healthz  200 "ok" while the daemon runs (liveness: restart it when this fails).
//   GET /readyz   200 "ready" once every map is recovered and until shutdown begins; 503 with the
//                 reason before and after (readiness: send it traffic only when this passes).
// Thread-safety: the handlers run on httplib's threads; `ready` must be safe to call from them.
#pragma once

#include <httplib.h>

#include <functional>
#include <string>

namespace fremen::server {

// nullopt-like: "" when ready, else why not ("recovering the maps", "shutting down").
using ReadinessProbe = std::function<std::string()>;

void AddHealthRoutes(httplib::Server& server, ReadinessProbe not_ready_because);

}  // namespace fremen::server
