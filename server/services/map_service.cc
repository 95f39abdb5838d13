#include "server/services/map_service.h"

#include <algorithm>

#include "server/convert/map_convert.h"
#include "server/rpc/map_name.h"
#include "storage/map_page.h"

namespace fremen::server {

namespace {

constexpr MethodSpec kCreateMap{"CreateMap", Access::kWrite, /*blocking=*/true};
constexpr MethodSpec kGetMap{"GetMap", Access::kRead, /*blocking=*/false};
constexpr MethodSpec kListMaps{"ListMaps", Access::kRead, /*blocking=*/false};
constexpr MethodSpec kDeleteMap{"DeleteMap", Access::kWrite, /*blocking=*/true};

}  // namespace

grpc::ServerUnaryReactor* MapServiceImpl::CreateMap(grpc::CallbackServerContext* context,
                                                    const v1::CreateMapRequest* request,
                                                    v1::CreateMapResponse* response) {
  return ServeUnary(deps_, context, kCreateMap, [this, context, request, response]() -> absl::Status {
    auto name = ResolveMapName(*context, request->map().name(), "map.name");
    if (!name.ok()) return name.status();
    v1::Map spec = request->map();
    spec.set_name(*name);
    auto info = MapInfoFromProto(spec);
    if (!info.ok()) return info.status();
    auto store = deps_.store->Get();
    if (!store.ok()) return store.status();
    auto created = (*store)->CreateMap(*std::move(info));
    if (!created.ok()) return RenameStorageFields(created.status());
    MapInfoToProto(*created, *response->mutable_map());
    AddMoveState(**store, *response->mutable_map());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* MapServiceImpl::GetMap(grpc::CallbackServerContext* context,
                                                 const v1::GetMapRequest* request, v1::GetMapResponse* response) {
  return ServeUnary(deps_, context, kGetMap, [this, context, request, response]() -> absl::Status {
    auto name = ResolveMapName(*context, request->map(), "map");
    if (!name.ok()) return name.status();
    auto store = deps_.store->Get();
    if (!store.ok()) return store.status();
    auto info = (*store)->GetMap(*name);
    if (!info.ok()) return info.status();
    MapInfoToProto(*info, *response->mutable_map());
    AddMoveState(**store, *response->mutable_map());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* MapServiceImpl::ListMaps(grpc::CallbackServerContext* context,
                                                   const v1::ListMapsRequest* request,
                                                   v1::ListMapsResponse* response) {
  return ServeUnary(deps_, context, kListMaps, [this, request, response]() -> absl::Status {
    if (request->page_size() < 0) {
      return absl::InvalidArgumentError(absl::StrCat("page_size must be ≥ 0, got ", request->page_size()));
    }
    // Google's API guidelines: a page size above the maximum is taken as the maximum.
    const size_t page_size = std::min<size_t>(request->page_size(), storage::kMaxPageSize);
    auto store = deps_.store->Get();
    if (!store.ok()) return store.status();
    auto page = (*store)->ListMaps(page_size, request->page_token());
    if (!page.ok()) return page.status();
    for (const storage::MapInfo& info : page->maps) {
      v1::Map& map = *response->add_maps();
      MapInfoToProto(info, map);
      AddMoveState(**store, map);
    }
    response->set_next_page_token(page->next_page_token);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* MapServiceImpl::DeleteMap(grpc::CallbackServerContext* context,
                                                    const v1::DeleteMapRequest* request,
                                                    v1::DeleteMapResponse* /*response*/) {
  return ServeUnary(deps_, context, kDeleteMap, [this, context, request]() -> absl::Status {
    auto name = ResolveMapName(*context, request->map(), "map");
    if (!name.ok()) return name.status();
    auto store = deps_.store->Get();
    if (!store.ok()) return store.status();
    return (*store)->DeleteMap(*name);
  });
}

}  // namespace fremen::server
