// The checks of one shard record on its own (its key's place, its value's decoding), shared by the
// verifier (storage/verify.h), which reports what fails them, and the salvage (storage/salvage.h),
// which keeps only what passes them. The checks that tie records together (a lossless history has
// its state) are the callers'.
// Thread-safety: const methods, callable from any thread.
#pragma once

#include <cstdint>
#include <string_view>

#include "absl/status/statusor.h"
#include "storage/cell_key.h"
#include "storage/map_info.h"
#include "storage/model/model_settings.h"
#include "storage/static_bricks.h"

namespace fremen::storage {

class ShardRecordChecks {
 public:
  // REQUIRES: info and settings outlive this.
  ShardRecordChecks(const MapInfo& info, const model::ModelSettings& settings, uint32_t shard)
      : info_(info), settings_(settings), shard_(shard), keys_(info.grid.keys()) {}

  // The key's place: this shard, and a cell of the grid. DataLoss saying where it belongs otherwise.
  absl::Status Place(uint64_t key) const;
  // A never-changed brick: decodes, and each of its states is in place (DataLoss naming the first
  // that is not; the decoded brick is still returned through `brick` for a caller that lists keys).
  absl::Status Static(uint64_t brick_key, std::string_view value, StaticBrick* brick = nullptr) const;
  absl::Status Dynamic(uint64_t key, std::string_view value) const;
  // Without its state: the caller's.
  absl::Status Lossless(std::string_view value) const;
  absl::Status Published(std::string_view value) const;
  absl::Status Wide(std::string_view value) const;
  absl::Status Label(uint64_t key, std::string_view value) const;

 private:
  const MapInfo& info_;
  const model::ModelSettings& settings_;
  const uint32_t shard_;
  const GridKeys keys_;
};

}  // namespace fremen::storage
