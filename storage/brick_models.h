// BrickModels: a copy of a shard's published models laid out brick by brick, which is how a region
// reads them (Shard::PredictBox).
//
// A shard's CompactModels hold a state's record at its dynamic index, in the order states became
// dynamic. A region visits the states brick by brick, so it read its records scattered over the whole
// table: a published check and a prefetched record per dynamic cell, about 60 bytes from a random
// place each (7 MB for a 1M-cell box with 12 % dynamic cells), which does not stay in cache
// (docs/performance.md, "A brick's models in one run"). Here the models of each brick's dynamic
// cells that had a published model when the copy was made sit one after another, as columns
// (model::ModelColumns) with each one's row-major index in the brick beside them, so that a brick's
// cells go through the region kernel (model::PredictColumns) as one consecutive run, read front to
// back. The columns hold each model at its own order: a region at a fixed order, or with
// persistence, reads the records as before.
//
// The copy is derived data: it is never written to disk and is made again when it is out of date.
// It covers, for each brick, the dynamic cells its image listed when it was made (`covered`): those
// with a published model are copied; the others (no model yet) are listed, and answered the usual
// way, as are the cells that became dynamic after it. A published record that changes (a
// publication, a restore) makes the whole copy out of date: the shard counts those changes
// (Shard's models generation) and the copy remembers the count it was made at.
//
// Thread-safety: immutable once built; any number of readers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "storage/brick_region.h"
#include "storage/model/kernels/compact_models.h"
#include "storage/model/kernels/model_columns.h"

namespace fremen::storage {

class BrickModels {
 public:
  struct Brick {
    uint32_t first = 0;   // its copied models: [first, first + count) of models()
    uint32_t count = 0;
    int terms = 0;        // the highest own order among them (at most the max order)
    uint32_t covered = 0;  // the image's dynamic cells [0, covered) are copied or listed in others
    uint32_t others_first = 0;  // its covered cells without a published model: others()[first, + count)
    uint32_t others_count = 0;
  };

  // From images[i], the image of brick i, and `models`, the shard's published models, at the shard's
  // models generation `generation`. REQUIRES: neither changes while this runs.
  BrickModels(std::span<const BrickImage> images, const model::CompactModels& models, uint64_t generation);

  uint64_t generation() const { return generation_; }
  // The bricks covered: those that existed when the copy was made, 0..size()-1.
  size_t size() const { return bricks_.size(); }
  const Brick& brick(size_t i) const { return bricks_[i]; }
  // The copied models, each brick's in a run.
  const model::ModelColumns& models() const { return models_; }
  // The row-major index in its brick of the cell of each copied model.
  uint16_t cell(size_t i) const { return cells_[i]; }
  const uint16_t* cells() const { return cells_.data(); }
  // The covered dynamic cells that had no published model.
  const BrickImage::DynamicCell* others() const { return others_.data(); }
  size_t memory_bytes() const;

 private:
  uint64_t generation_;
  std::vector<Brick> bricks_;
  model::ModelColumns models_;
  std::vector<uint16_t> cells_;
  std::vector<BrickImage::DynamicCell> others_;
};

}  // namespace fremen::storage
