// The types of a map's queries (MapStore::Predict, PredictBox, Snapshot): how to predict, a box of
// grid cells, and a copy of one state's model.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

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
