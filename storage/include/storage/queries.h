// The types of a map's queries (MapStore::Predict, PredictBox, PlanBoxSeries, Snapshot): how to
// predict, a box of grid cells (and its plan at many times), and a copy of one state's model.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "storage/model/lossless/lossless_history.h"
#include "storage/model/state_model.h"
#include "storage/model/static_state.h"

namespace fremen::storage {

struct PredictOptions {
  bool persistence = false;  // blend in the last observation (the persistence model)
  int order = -1;            // -1: each state's selected order
};

// A box of grid cells, [lo, hi) per axis.
struct CellBox {
  std::array<uint32_t, 3> lo = {0, 0, 0};
  std::array<uint32_t, 3> hi = {0, 0, 0};
  uint64_t cell_count() const { return uint64_t{hi[0] - lo[0]} * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
};

// A box of a grid at many times (MapStore::PlanBoxSeries, PredictBoxSeries), split once into the
// cells whose p(t) cannot change with t under the plan's options — unobserved (0.5), never changed,
// a model without components to use (no published model, or order 0) and no persistence — and
// the others, the varying cells, predicted at each time.
struct BoxSeries {
  CellBox box;
  PredictOptions options;
  // p of every constant cell at its index in the box (x fastest, then y, then z), bit for bit
  // what PredictBox gives at any time; a varying cell's entry is unspecified.
  std::vector<float> constant;
  // The varying cells' indices in the box, ascending, and their keys.
  std::vector<uint32_t> varying;
  std::vector<uint64_t> varying_keys;
  // The map store's, by shard: the varying cells' states (dynamic indices, in record order) and
  // their positions in `varying`.
  struct ShardPart {
    std::vector<uint32_t> dynamic, at;
  };
  std::vector<ShardPart> shards;
};

// A copy of one state's complete model, for the full-model view and for tests.
struct StateSnapshot {
  bool is_static = true;
  model::StaticState static_state;               // when is_static
  std::optional<model::CompactStateModel> model;  // when dynamic
  std::optional<model::LosslessHistory> lossless;
  std::string name, group;
};

// The value an unobserved state predicts: no information either way.
inline constexpr float kUnobservedProbability = 0.5f;

}  // namespace fremen::storage
