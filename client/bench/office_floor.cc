#include "client/bench/office_floor.h"

#include <algorithm>
#include <cmath>

namespace fremen::bench {
namespace {

// The floor plan, in cells: a corridor across the middle, eight rooms on each side of it.
constexpr uint32_t kWall = 2;                 // wall thickness
constexpr uint32_t kCorridorY0 = 170;         // first row of the corridor's interior
constexpr uint32_t kCorridorY1 = 195;         // one past its last row
constexpr uint32_t kLaneY0 = 180;             // the rows people walk along
constexpr uint32_t kLaneY1 = 186;
constexpr uint32_t kRoomWidth = OfficeFloor::kWidth / 8;  // 73 cells
constexpr uint32_t kDoorOffset = 28;          // a room's door, from its left wall
constexpr uint32_t kDoorWidth = 16;           // 80 cm
constexpr int kDesksPerRoom = 3;
constexpr int kCupboardOpenings = 3;          // a day, a few minutes each

uint64_t Mix(uint64_t x) {  // splitmix64's finaliser: a well-spread hash of x
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
// A uniform number in [0, 1) from the hash of (a, b, c).
double Uniform(uint64_t a, uint64_t b, uint64_t c = 0) {
  return static_cast<double>(Mix(Mix(Mix(a) ^ b) ^ c) >> 11) * 0x1.0p-53;
}

struct Clock {
  int64_t day;   // days since the epoch
  int weekday;   // 0 = Monday
  double hour;   // of the day, UTC
};
Clock At(double time) {
  const int64_t day = static_cast<int64_t>(std::floor(time / 86400));
  return {day, static_cast<int>(((day + 3) % 7 + 7) % 7), (time - 86400.0 * static_cast<double>(day)) / 3600};
}

}  // namespace

void OfficeFloor::AddRect(std::vector<uint32_t>& cells, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1) const {
  for (uint32_t y = y0; y < y1; ++y) {
    for (uint32_t x = x0; x < x1; ++x) cells.push_back(x + kWidth * y);
  }
}

OfficeFloor::OfficeFloor(uint64_t seed) : seed_(seed), static_bits_((kCells + 7) / 8, 0) {
  std::vector<uint32_t> walls, furniture;
  AddRect(walls, 0, 0, kWidth, kWall);
  AddRect(walls, 0, kHeight - kWall, kWidth, kHeight);
  AddRect(walls, 0, 0, kWall, kHeight);
  AddRect(walls, kWidth - kWall, 0, kWidth, kHeight);
  AddRect(walls, 0, kCorridorY0 - kWall, kWidth, kCorridorY0);  // the corridor's two walls
  AddRect(walls, 0, kCorridorY1, kWidth, kCorridorY1 + kWall);
  uint64_t salt = 0;
  for (uint32_t room = 0; room < 8; ++room) {
    const uint32_t x0 = room * kRoomWidth;
    AddRect(walls, x0, 0, x0 + kWall, kHeight);  // the walls between rooms (the corridor's cut out below)
    for (int side = 0; side < 2; ++side) {
      // The room's extent in y (inside its walls), and the wall it shares with the corridor.
      const uint32_t ry0 = side == 0 ? kWall : kCorridorY1 + kWall;
      const uint32_t ry1 = side == 0 ? kCorridorY0 - kWall : kHeight - kWall;
      const uint32_t wall_y0 = side == 0 ? kCorridorY0 - kWall : kCorridorY1;
      Element door{Element::Kind::kDoor, ++salt, {}};
      AddRect(door.cells, x0 + kDoorOffset, wall_y0, x0 + kDoorOffset + kDoorWidth, wall_y0 + kWall);
      elements_.push_back(std::move(door));
      for (int d = 0; d < kDesksPerRoom; ++d) {
        const uint32_t dx = x0 + 8 + 20 * static_cast<uint32_t>(d);
        const uint32_t dy = side == 0 ? ry0 + 20 : ry1 - 35;
        AddRect(furniture, dx, dy, dx + 16, dy + 10);  // the desk top
        Element chair{Element::Kind::kDesk, ++salt, {}};
        AddRect(chair.cells, dx + 4, dy + 10, dx + 12, dy + 18);
        elements_.push_back(std::move(chair));
      }
      // A cupboard against the far wall, its door swinging into the room.
      const uint32_t cy = side == 0 ? ry0 : ry1 - 10;
      AddRect(furniture, x0 + 40, cy, x0 + 70, cy + 10);
      Element cupboard{Element::Kind::kCupboard, ++salt, {}};
      AddRect(cupboard.cells, x0 + 40, side == 0 ? cy + 10 : cy - 3, x0 + 70, side == 0 ? cy + 13 : cy);
      elements_.push_back(std::move(cupboard));
    }
  }
  Element lane{Element::Kind::kCorridor, ++salt, {}};
  AddRect(lane.cells, kWall, kLaneY0, kWidth - kWall, kLaneY1);
  elements_.push_back(std::move(lane));

  for (uint32_t c : walls) {
    const uint32_t x = c % kWidth, y = c / kWidth;
    const bool in_corridor = y >= kCorridorY0 && y < kCorridorY1 && x > kWall && x < kWidth - kWall;
    if (!in_corridor) static_bits_[c / 8] |= static_cast<uint8_t>(1u << (c % 8));
  }
  for (uint32_t c : furniture) static_bits_[c / 8] |= static_cast<uint8_t>(1u << (c % 8));
  for (Element& e : elements_) {
    std::sort(e.cells.begin(), e.cells.end());
    // A dynamic cell's static bit is 0: its state comes from its element alone.
    for (uint32_t c : e.cells) static_bits_[c / 8] &= static_cast<uint8_t>(~(1u << (c % 8)));
    dynamic_cells_ += e.cells.size();
  }
}

bool OfficeFloor::ElementOccupied(const Element& e, uint32_t cell, double time) const {
  const Clock clock = At(time);
  const bool workday = clock.weekday < 5;
  const auto jitter = [&](uint64_t k) { return Uniform(seed_ ^ e.salt, static_cast<uint64_t>(clock.day), k) - 0.5; };
  switch (e.kind) {
    case Element::Kind::kDoor: {  // occupied = closed
      const bool open = workday && clock.hour >= 8 + jitter(1) && clock.hour < 18 + jitter(2);
      return !open;
    }
    case Element::Kind::kDesk: {
      if (!workday || jitter(0) < -0.4) return false;  // a weekend, or a day off (one in ten)
      const double lunch = 12 + jitter(3);
      const bool at_work = clock.hour >= 9 + jitter(1) && clock.hour < 17.5 + jitter(2);
      return at_work && !(clock.hour >= lunch && clock.hour < lunch + 0.75);
    }
    case Element::Kind::kCupboard: {
      for (int k = 0; k < kCupboardOpenings; ++k) {
        const double start = 8 + 10 * (jitter(10 + static_cast<uint64_t>(k)) + 0.5);
        if (clock.hour >= start && clock.hour < start + 4.0 / 60) return true;
      }
      return false;
    }
    case Element::Kind::kCorridor: {
      const bool busy = workday && clock.hour >= 8 && clock.hour < 18;
      const uint64_t scan = static_cast<uint64_t>(std::llround(time * 1000));
      return Uniform(seed_ ^ e.salt, cell, scan) < (busy ? 0.02 : 0.001);
    }
  }
  return false;
}

std::string OfficeFloor::Occupied(uint64_t first, uint64_t count, double time) const {
  std::string out((count + 7) / 8, '\0');
  // The static bits shifted so that cell `first` is bit 0.
  const uint64_t byte = first / 8;
  const unsigned shift = first % 8;
  for (size_t j = 0; j < out.size(); ++j) {
    const unsigned lo = static_bits_[byte + j];
    const unsigned hi = byte + j + 1 < static_bits_.size() ? static_bits_[byte + j + 1] : 0;
    out[j] = static_cast<char>(((lo | hi << 8) >> shift) & 0xff);
  }
  if (count % 8 != 0) out.back() = static_cast<char>(static_cast<uint8_t>(out.back()) & ((1u << (count % 8)) - 1));
  for (const Element& e : elements_) {
    const auto begin = std::lower_bound(e.cells.begin(), e.cells.end(), first);
    const auto end = std::lower_bound(begin, e.cells.end(), first + count);
    if (begin == end) continue;
    const bool together = e.kind != Element::Kind::kCorridor;
    const bool state = together && ElementOccupied(e, 0, time);
    for (auto c = begin; c != end; ++c) {
      if (together ? state : ElementOccupied(e, *c, time)) {
        const uint64_t i = *c - first;
        out[i / 8] = static_cast<char>(static_cast<uint8_t>(out[i / 8]) | (1u << (i % 8)));
      }
    }
  }
  return out;
}

}  // namespace fremen::bench
