// Client: connecting and the MapService calls.
#include "client/lib/client.h"

namespace fremen::client {

absl::StatusOr<Client> Client::Connect(ConnectionOptions options) {
  auto connection = Connection::Open(std::move(options));
  if (!connection.ok()) return connection.status();
  return Client(*std::move(connection));
}

absl::StatusOr<v1::Map> Client::CreateMap(const v1::Map& map, const CallOptions& call) const {
  v1::CreateMapRequest request;
  *request.mutable_map() = map;
  v1::CreateMapResponse response;
  absl::Status status = connection_->CallOnce(call, map.name(), [&](grpc::ClientContext& context) {
    return connection_->maps().CreateMap(&context, request, &response);
  });
  if (!status.ok()) return status;
  return std::move(*response.mutable_map());
}

absl::StatusOr<v1::Map> Client::GetMap(absl::string_view map, const CallOptions& call) const {
  v1::GetMapRequest request;
  request.set_map(std::string(map));
  v1::GetMapResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->maps().GetMap(&context, request, &response);
  });
  if (!status.ok()) return status;
  return std::move(*response.mutable_map());
}

absl::StatusOr<MapPage> Client::ListMaps(int page_size, const std::string& page_token, const CallOptions& call) const {
  v1::ListMapsRequest request;
  request.set_page_size(page_size);
  request.set_page_token(page_token);
  v1::ListMapsResponse response;
  absl::Status status = connection_->CallIdempotent(call, "", [&](grpc::ClientContext& context) {
    return connection_->maps().ListMaps(&context, request, &response);
  });
  if (!status.ok()) return status;
  MapPage page;
  page.maps.assign(std::make_move_iterator(response.mutable_maps()->begin()),
                   std::make_move_iterator(response.mutable_maps()->end()));
  page.next_page_token = response.next_page_token();
  return page;
}

absl::StatusOr<std::vector<v1::Map>> Client::ListAllMaps(const CallOptions& call) const {
  std::vector<v1::Map> maps;
  std::string token;
  do {
    auto page = ListMaps(0, token, call);
    if (!page.ok()) return page.status();
    for (v1::Map& map : page->maps) maps.push_back(std::move(map));
    token = page->next_page_token;
  } while (!token.empty());
  return maps;
}

absl::Status Client::DeleteMap(absl::string_view map, const CallOptions& call) const {
  v1::DeleteMapRequest request;
  request.set_map(std::string(map));
  v1::DeleteMapResponse response;
  return connection_->CallOnce(call, map, [&](grpc::ClientContext& context) {
    return connection_->maps().DeleteMap(&context, request, &response);
  });
}

}  // namespace fremen::client
