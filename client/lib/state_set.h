// How the client names states: grid cells by index (Cell), by metric point (Point), generic states
// by 64-bit id or by name. State makes one v1::StateRef (GetStateModel); StateSet makes the
// v1::StateRefs of many states of one kind (Predict, CheckAnomalies).
// Thread-safety: values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fremen/v1/common.pb.h"

namespace fremen::client {

// A grid cell's integer indices; z is 0 in a 2-D grid.
struct Cell {
  uint32_t x = 0, y = 0, z = 0;
  bool operator==(const Cell&) const = default;
};

// A metric point in the map's frame, metres.
struct Point {
  double x = 0, y = 0, z = 0;
};

// Cells along x, y and z (a grid, a box, a patch). z = 1 for one plane.
struct GridShape {
  uint32_t x = 0, y = 0, z = 1;
  uint64_t cells() const { return uint64_t{x} * y * z; }
  bool operator==(const GridShape&) const = default;
};

class State {
 public:
  static v1::StateRef AtCell(Cell cell);
  static v1::StateRef AtPoint(Point point);
  static v1::StateRef WithId(uint64_t id);
  static v1::StateRef Named(std::string name);
};

// Many states of one kind, in the order results come back.
class StateSet {
 public:
  static StateSet Cells(const std::vector<Cell>& cells);
  static StateSet Points(const std::vector<Point>& points);
  static StateSet Ids(const std::vector<uint64_t>& ids);
  static StateSet Names(const std::vector<std::string>& names);

  size_t size() const { return size_; }
  const v1::StateRefs& proto() const { return refs_; }

 private:
  v1::StateRefs refs_;
  size_t size_ = 0;
};

}  // namespace fremen::client
