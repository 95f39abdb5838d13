// What PredictRegion and PredictRegionSeries check alike: the map (a grid), the box [lo, hi), the
// prediction options, the output and its confidence — each error naming the field.
// Thread-safe.
#pragma once

#include <grpcpp/server_context.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "fremen/v1/query.pb.h"
#include "server/rpc/store_handle.h"
#include "storage/map_store.h"

namespace fremen::server {

struct RegionRequest {
  std::shared_ptr<storage::MapStore> map;
  storage::CellBox box;
  storage::PredictOptions options;
  v1::RegionOutput output = v1::REGION_OUTPUT_FLOAT;  // UNSPECIFIED normalised
};

absl::StatusOr<RegionRequest> PrepareRegion(const StoreHandle& store, const grpc::ServerContextBase& context,
                                            const std::string& map, const v1::CellIndex& lo, const v1::CellIndex& hi,
                                            const v1::PredictionOptions& options, int output, float confidence);

}  // namespace fremen::server
