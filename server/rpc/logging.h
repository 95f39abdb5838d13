// fremend's logs: named spdlog loggers on one stderr sink (journald keeps it under systemd):
//   "fremend"  the daemon's life: start steps, listening address, shutdown;
//   "access"   one line per RPC (server/rpc/access_log.h);
//   "store"    the store as the daemon sees it: recovery, closing;
//   "grpc"     gRPC's own messages, routed here instead of its separate format.
// Set up once at start, before any thread; the loggers are thread-safe.
#pragma once

#include <spdlog/logger.h>

#include <memory>

#include "absl/strings/string_view.h"

namespace fremen::server {

inline constexpr char kDaemonLogger[] = "fremend";
inline constexpr char kStoreLogger[] = "store";
inline constexpr char kGrpcLogger[] = "grpc";

// REQUIRES: `level` is one the config accepts (server/daemon/config.h log_level).
void SetUpLogging(absl::string_view level);

// The logger named `name` (one of the above), or spdlog's default one when SetUpLogging has not run
// (a scheduler, a service or a daemon inside a unit test), so that code never checks for null.
std::shared_ptr<spdlog::logger> NamedLogger(const char* name);
inline std::shared_ptr<spdlog::logger> DaemonLog() { return NamedLogger(kDaemonLogger); }

}  // namespace fremen::server
