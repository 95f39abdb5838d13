#include "server/services/region_request.h"

#include "server/convert/query_args.h"
#include "server/rpc/map_lookup.h"
#include "server/services/region_plan.h"

namespace fremen::server {

absl::StatusOr<RegionRequest> PrepareRegion(const StoreHandle& store, const grpc::ServerContextBase& context,
                                            const std::string& map, const v1::CellIndex& lo, const v1::CellIndex& hi,
                                            const v1::PredictionOptions& options, int output, float confidence) {
  RegionRequest region;
  auto found = LookUpMap(store, context, map);
  if (!found.ok()) return found.status();
  region.map = *std::move(found);
  const storage::MapInfo& info = region.map->info();
  auto box = RegionBoxOf(info, lo, hi);
  if (!box.ok()) return box.status();
  region.box = *box;
  auto predict = PredictOptionsOf(info, options, "options");
  if (!predict.ok()) return predict.status();
  region.options = *predict;
  auto kind = RegionOutputOf(output);
  if (!kind.ok()) return kind.status();
  region.output = *kind;
  if (region.output == v1::REGION_OUTPUT_STATES) {
    if (absl::Status s = CheckConfidence(confidence, 0, 1, "confidence"); !s.ok()) return s;
  }
  return region;
}

}  // namespace fremen::server
