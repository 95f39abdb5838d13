// The paper's office at its size, for fremen_office_load: a deterministic floor of about 213,000
// cells (5 cm) that a robot's sensors cover whole every 5 s, most of it static (walls, furniture,
// free floor) and a few percent dynamic. It scales up the demo's office (client/formats/
// office_simulator.h) from one room to a floor of rooms off a corridor:
// - room doors: closed (occupied) outside working hours, open on weekdays from about 8:00 to
//   18:00, each door with its own jittered times each day;
// - desks: the chair area of each desk is occupied while its owner sits there (weekdays, around
//   9:00-17:30, out for lunch), with per-desk, per-day jitter;
// - the corridor: people walk through by day, so a corridor cell is occupied now and then
//   (independently per scan), rarely at night;
// - cupboards: their doors stand open for a few minutes a few times a day.
// Occupancy is a pure function of (cell, time); thread-safe once built.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fremen::bench {

class OfficeFloor {
 public:
  // The floor plan; `seed` fixes the jitter of every door, desk and cupboard.
  explicit OfficeFloor(uint64_t seed = 1);

  static constexpr uint32_t kWidth = 584;   // cells along x: 29.2 m
  static constexpr uint32_t kHeight = 365;  // cells along y: 18.25 m
  static constexpr double kResolution = 0.05;
  static constexpr uint64_t kCells = uint64_t{kWidth} * kHeight;

  // Cells whose state ever changes.
  uint64_t DynamicCells() const { return dynamic_cells_; }

  // The occupied bits of cells [first, first + count) (linear index x + kWidth·y) at `time`
  // (seconds since the Unix epoch, UTC), bit i of byte i / 8 for cell first + i, as
  // CompactCells.occupied wants them. REQUIRES: first + count ≤ kCells.
  std::string Occupied(uint64_t first, uint64_t count, double time) const;

 private:
  // A group of cells that change together (a door leaf, a chair area, a cupboard door), or, for the
  // corridor, cells that each change on their own.
  struct Element {
    enum class Kind { kDoor, kDesk, kCupboard, kCorridor } kind;
    uint64_t salt;                  // per-element jitter
    std::vector<uint32_t> cells;    // sorted linear indices
  };
  // Whether an element's cells are occupied at `time` (for the corridor: cell `cell`'s).
  bool ElementOccupied(const Element& e, uint32_t cell, double time) const;
  void AddRect(std::vector<uint32_t>& cells, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1) const;

  uint64_t seed_;
  std::vector<uint8_t> static_bits_;  // occupied bits at every time (walls, furniture), by cell
  std::vector<Element> elements_;
  uint64_t dynamic_cells_ = 0;
};

}  // namespace fremen::bench
