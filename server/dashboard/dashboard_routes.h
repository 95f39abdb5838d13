// The web dashboard on the HTTP port (docs/http.md, "Dashboard"), from the embedded files:
//   GET /               index.html
//   GET /static/<name>  an embedded file; 404 for a name that is not one
//   GET /favicon.ico    favicon.svg
// Each answer carries its ETag and Cache-Control: no-cache (the browser keeps the file and asks
// again each time with If-None-Match; the same bytes answer 304 with no body), so a new fremend's
// dashboard is never hidden behind a stale cache. No token is needed: the files hold no data; the
// pages' API calls carry the token the user types.
// Thread-safety: the handlers read constant data only.
#pragma once

#include <httplib.h>

namespace fremen::server {

void AddDashboardRoutes(httplib::Server& server);

}  // namespace fremen::server
