// fremen.v1.MapService over storage::Store: create, get, list and delete maps.
// CreateMap and DeleteMap wait on disk (catalog commits, opening or removing a map's files) and run
// on the blocking pool; GetMap and ListMaps read the catalog and run inline.
// Thread-safety: gRPC calls the handlers from any thread; the service holds no state of its own.
#pragma once

#include "fremen/v1/maps.grpc.pb.h"
#include "server/rpc/unary_call.h"

namespace fremen::server {

class MapServiceImpl final : public v1::MapService::CallbackService {
 public:
  explicit MapServiceImpl(const ServiceDeps& deps) : deps_(deps) {}

  grpc::ServerUnaryReactor* CreateMap(grpc::CallbackServerContext* context, const v1::CreateMapRequest* request,
                                      v1::CreateMapResponse* response) override;
  grpc::ServerUnaryReactor* GetMap(grpc::CallbackServerContext* context, const v1::GetMapRequest* request,
                                   v1::GetMapResponse* response) override;
  grpc::ServerUnaryReactor* ListMaps(grpc::CallbackServerContext* context, const v1::ListMapsRequest* request,
                                     v1::ListMapsResponse* response) override;
  grpc::ServerUnaryReactor* DeleteMap(grpc::CallbackServerContext* context, const v1::DeleteMapRequest* request,
                                      v1::DeleteMapResponse* response) override;

 private:
  const ServiceDeps deps_;
};

}  // namespace fremen::server
