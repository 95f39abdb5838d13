// Generated scans for the store's tests: a robot sweeping a grid, the cells of a few "doors"
// opening and closing on a daily rhythm, the rest always free. Deterministic for a seed.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "storage/batch.h"
#include "storage/cell_key.h"
#include "storage/map_info.h"

namespace fremen::storage::testing {

inline MapInfo GridMap(const std::string& name, uint32_t nx, uint32_t ny, uint32_t nz, uint32_t shards) {
  MapInfo info;
  info.name = name;
  info.grid.resolution = 0.1;
  info.grid.size = {nx, ny, nz};
  info.shards = shards;
  return info;
}

// Scan `i` (sequence i + 1): time t0 + i·600 s, a random subset of about `cells` cells of the grid;
// cells with x % 7 == 0 follow a daily square wave with 5% noise, the rest are always 0.
inline ObservationBatch SweepScan(const MapInfo& map, uint64_t writer, uint64_t i, size_t cells, uint64_t seed = 1) {
  std::mt19937_64 rng(seed * 1000003 + i);
  ObservationBatch b;
  b.writer_id = writer;
  b.sequence = i + 1;
  b.time = 1.7e9 + 600.0 * static_cast<double>(i);
  const double day_phase = std::fmod(b.time, 86400.0) / 86400.0;
  std::bernoulli_distribution noise(0.05);
  std::uniform_int_distribution<uint32_t> ux(0, map.grid.size[0] - 1), uy(0, map.grid.size[1] - 1),
      uz(0, map.grid.size[2] - 1);
  for (size_t c = 0; c < cells; ++c) {
    const uint32_t x = ux(rng), y = uy(rng), z = uz(rng);
    const bool dynamic = x % 7 == 0;
    const bool occupied = dynamic && ((day_phase > 0.3 && day_phase < 0.7) != noise(rng));
    b.keys.push_back(map.grid.keys().Key(x, y, z));
    b.values.push_back(occupied ? 1.0f : 0.0f);
  }
  return b;
}

}  // namespace fremen::storage::testing
