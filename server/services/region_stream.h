// PredictRegion: a box of a grid at one time, streamed to the client in chunks
// (server/services/region_plan.h), as a BlockStream (server/services/block_stream.h).
//
// The box is computed a block at a time (up to 256k cells: one MapStore::PredictBox call, which
// spreads it over the map's shards), and each block is cut into chunks of at most 1 MiB, the
// messages. Floats and bytes are predicted into the chunk's own buffer, the one gRPC sends.
//
// Thread-safety: as BlockStream's.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "fremen/v1/query.pb.h"
#include "server/rpc/unary_call.h"
#include "server/services/block_stream.h"
#include "server/services/region_plan.h"
#include "storage/map_store.h"

namespace fremen::server {

class RegionStream final : public BlockStream<v1::PredictRegionRequest, v1::PredictRegionResponse> {
 public:
  // Starts the call; the reactor deletes itself once the call is done.
  static RegionStream* Start(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                             const grpc::ByteBuffer& request);

 private:
  RegionStream(const ServiceDeps& deps, grpc::CallbackServerContext* context);
  absl::Status Prepare(const v1::PredictRegionRequest& request) override;
  absl::Status ComputeBlock(uint64_t i, Chunks& chunks, uint64_t& more_blocks) override;
  bool ComputesInline(uint64_t i) const override;

  // Fixed by Prepare.
  std::shared_ptr<storage::MapStore> map_;
  std::optional<RegionPlan> blocks_;  // of the box
  uint64_t chunk_cells_ = 0;          // per message
  storage::PredictOptions options_;
  double time_ = 0;
  v1::RegionOutput output_ = v1::REGION_OUTPUT_FLOAT;
  float confidence_ = 0.5f;

  // The computing thread's (one at a time).
  std::vector<float> scratch_;
  Response message_;  // a chunk's fields
};

}  // namespace fremen::server
