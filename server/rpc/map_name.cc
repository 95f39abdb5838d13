#include "server/rpc/map_name.h"

#include "absl/strings/str_cat.h"

namespace fremen::server {

absl::StatusOr<std::string> ResolveMapName(const grpc::ServerContextBase& context, absl::string_view request_map,
                                           absl::string_view field) {
  const auto& metadata = context.client_metadata();
  const auto it = metadata.find(kMapHeader);
  std::optional<absl::string_view> header;
  if (it != metadata.end()) header = absl::string_view(it->second.data(), it->second.size());
  return ResolveMapName(header, request_map, field);
}

absl::StatusOr<std::string> ResolveMapName(std::optional<absl::string_view> header, absl::string_view request_map,
                                           absl::string_view field) {
  if (header && !header->empty()) {
    if (!request_map.empty() && request_map != *header) {
      return absl::InvalidArgumentError(absl::StrCat(field, " is \"", request_map, "\" but the ", kMapHeader,
                                                     " header says \"", *header, "\"; they must agree"));
    }
    return std::string(*header);
  }
  if (request_map.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(field, " is required (or the ", kMapHeader, " header)"));
  }
  return std::string(request_map);
}

}  // namespace fremen::server
