// The demo's simulated office: a deterministic (seeded) stretch of days in a small office seen by a
// patrolling robot, as observation batches for a grid map and for a generic-state map. It gives a
// newcomer daily and weekly rhythms for FreMEn to find:
// - generic states: "door" (the office door: open on weekdays in working hours, with jittered
//   opening and closing times and rare visits at other times), "meeting-room" (occupied at the
//   daily stand-up and the Tuesday/Thursday meeting), "kitchen-light" (on around lunch);
// - a grid of the office (walls all round and a partition whose doorway is the door; desks whose
//   cells a person occupies in working hours; people walking in the corridor by day).
// Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "client/formats/observation_batches.h"

namespace fremen::formats {

struct OfficeOptions {
  // Same seed, same observations. Default: 1.
  uint64_t seed = 1;
  // Time of the first scan, seconds. Default: Monday 20 November 2023, 00:00 UTC, so that days
  // start on a Monday and working hours are in UTC.
  double start = 1700438400;
  // Days simulated. REQUIRES: > 0. Default: a week.
  double days = 7;
  // Seconds between the robot's scans. REQUIRES: > 0. Default: 10 minutes.
  double scan_interval = 600;
};

// The simulated grid: 40 × 20 cells of 0.25 m (10 m × 5 m), origin (0, 0).
inline constexpr uint32_t kOfficeWidth = 40;
inline constexpr uint32_t kOfficeHeight = 20;
inline constexpr double kOfficeResolution = 0.25;
// The doorway in the partition: cells (kDoorX, kDoorY0..kDoorY1) are occupied while the door is
// closed.
inline constexpr uint32_t kDoorX = 20;
inline constexpr uint32_t kDoorY0 = 9;
inline constexpr uint32_t kDoorY1 = 10;

struct OfficeWeek {
  // One scan of every cell of the grid per scan time.
  std::vector<CellBatch> grid_scans;
  // One observation of every generic state per scan time.
  std::vector<NamedStateBatch> state_scans;
};

OfficeWeek SimulateOffice(const OfficeOptions& options);

// Whether cell (x, y) is a wall (occupied at every time).
bool IsOfficeWall(uint32_t x, uint32_t y);

}  // namespace fremen::formats
