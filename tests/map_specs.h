// Test support: the maps end-to-end tests create, as fremen.v1.Map messages. Each builder sets only
// what it names; a test adds what it needs more (shards, z, origin, persistence, lossless history),
// so that a field a test never set stays unset in what the daemon is sent.
// Functions; thread-compatible.
#pragma once

#include <cstdint>
#include <string>

#include "fremen/v1/common.pb.h"
#include "fremen/v1/maps.pb.h"

namespace fremen::testing {

// A grid map `name` of nx × ny cells (z left unset) of `resolution` metres.
inline v1::Map GridMapSpec(const std::string& name, uint32_t nx, uint32_t ny, double resolution) {
  v1::Map map;
  map.set_name(name);
  map.set_kind(v1::MAP_KIND_GRID);
  map.mutable_grid()->set_resolution(resolution);
  map.mutable_grid()->mutable_size()->set_x(nx);
  map.mutable_grid()->mutable_size()->set_y(ny);
  return map;
}

// A generic map (labelled states) `name`.
inline v1::Map GenericMapSpec(const std::string& name) {
  v1::Map map;
  map.set_name(name);
  map.set_kind(v1::MAP_KIND_GENERIC);
  return map;
}

// Every cell of an nx × ny plane (z = 0), x fastest: the states of a request about a whole grid.
inline v1::StateRefs PlaneCells(uint32_t nx, uint32_t ny) {
  v1::StateRefs refs;
  for (uint32_t y = 0; y < ny; ++y) {
    for (uint32_t x = 0; x < nx; ++x) {
      refs.mutable_cells()->add_x(x);
      refs.mutable_cells()->add_y(y);
      refs.mutable_cells()->add_z(0);
    }
  }
  return refs;
}

}  // namespace fremen::testing
