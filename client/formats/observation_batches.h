// Observations grouped as the IngestService takes them: one batch per scan time, for a grid map
// (cells by index) or a generic map (states by name). Plain data; thread-compatible.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fremen::formats {

// One observation of one grid cell.
struct CellObservation {
  double t;
  uint32_t x, y, z;
  float s;
};

// One scan of a grid: parallel arrays, one element per observed cell.
struct CellBatch {
  double time = 0;
  std::vector<uint32_t> x, y, z;
  std::vector<float> values;

  void Add(uint32_t cx, uint32_t cy, uint32_t cz, float value) {
    x.push_back(cx);
    y.push_back(cy);
    z.push_back(cz);
    values.push_back(value);
  }
  size_t size() const { return values.size(); }
};

// One scan of generic states by name (a name seen for the first time becomes a new state).
struct NamedStateBatch {
  double time = 0;
  std::vector<std::string> names;
  std::vector<float> values;
};

// Groups cell observations into one batch per distinct time, in time order (observations of one
// time keep their input order).
std::vector<CellBatch> GroupByTime(const std::vector<CellObservation>& observations);

}  // namespace fremen::formats
