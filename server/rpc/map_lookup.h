// The open map a call is about: its name from the request's field or the x-fremen-map header
// (server/rpc/map_name.h), then the store — UNAVAILABLE while the daemon recovers, NOT_FOUND for a
// name it does not hold (docs/storage.md, "Maps across daemons": a daemon says so rather than
// guessing).
// Pure function over thread-safe objects; thread-safe.
#pragma once

#include <grpcpp/server_context.h>

#include <memory>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/rpc/map_name.h"
#include "server/rpc/store_handle.h"
#include "storage/map_store.h"

namespace fremen::server {

inline absl::StatusOr<std::shared_ptr<storage::MapStore>> LookUpMap(const StoreHandle& handle,
                                                                    const grpc::ServerContextBase& context,
                                                                    absl::string_view request_map,
                                                                    absl::string_view field = "map") {
  auto name = ResolveMapName(context, request_map, field);
  if (!name.ok()) return name.status();
  auto store = handle.Get();
  if (!store.ok()) return store.status();
  return (*store)->Map(*name);
}

}  // namespace fremen::server
