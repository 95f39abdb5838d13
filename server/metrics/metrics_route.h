// GET /metrics on the HTTP port: Metrics::Scrape in the Prometheus text format. When the daemon
// has tokens, the request needs a read (or write) token in "Authorization: Bearer <token>", checked
// by the same Authenticator as gRPC calls: 401 without one or with an unknown one (and a
// WWW-Authenticate challenge), with the google.rpc.Status JSON body of server/http/http_status.h. Prometheus sends it with
// `authorization: {credentials_file: ...}` in its scrape config (docs/http.md, "Metrics").
// Thread-safety: the handler runs on httplib's threads; `metrics` and `auth` must outlive the server.
#pragma once

#include <httplib.h>

#include "server/metrics/metrics.h"
#include "server/rpc/auth.h"

namespace fremen::server {

void AddMetricsRoute(httplib::Server& server, const Metrics* metrics, const Authenticator* auth);

}  // namespace fremen::server
