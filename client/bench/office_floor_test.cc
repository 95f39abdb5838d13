#include "client/bench/office_floor.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fremen::bench {
namespace {

constexpr double kMonday = 1700438400;  // Monday 20 November 2023, 00:00 UTC
constexpr double kHour = 3600;

bool Bit(const std::string& bits, uint64_t i) { return (static_cast<uint8_t>(bits[i / 8]) >> (i % 8)) & 1; }

uint64_t Count(const std::string& bits) {
  uint64_t n = 0;
  for (char c : bits) n += static_cast<unsigned>(__builtin_popcount(static_cast<uint8_t>(c)));
  return n;
}

TEST(OfficeFloor, IsThePapersOfficeSizeWithAFewPercentOfItDynamic) {
  const OfficeFloor floor;
  EXPECT_GT(OfficeFloor::kCells, 210'000u);
  EXPECT_LT(OfficeFloor::kCells, 216'000u);
  const double dynamic = static_cast<double>(floor.DynamicCells()) / OfficeFloor::kCells;
  EXPECT_GT(dynamic, 0.02);
  EXPECT_LT(dynamic, 0.06);
}

// Every cell the floor calls dynamic changes at least once in a week sampled each minute, and no
// other cell ever does: the walls and furniture stay, the free floor stays free.
TEST(OfficeFloor, ExactlyTheDynamicCellsChangeInAWeek) {
  const OfficeFloor floor;
  const std::string first = floor.Occupied(0, OfficeFloor::kCells, kMonday);
  std::vector<uint8_t> changed(OfficeFloor::kCells, 0);
  for (double t = kMonday + 60; t < kMonday + 7 * 24 * kHour; t += 60) {
    const std::string now = floor.Occupied(0, OfficeFloor::kCells, t);
    for (size_t j = 0; j < now.size(); ++j) {
      const uint8_t diff = static_cast<uint8_t>(now[j] ^ first[j]);
      for (unsigned b = 0; diff != 0 && b < 8; ++b) {
        if ((diff >> b) & 1) changed[j * 8 + b] = 1;
      }
    }
  }
  uint64_t n = 0;
  for (uint8_t c : changed) n += c;
  EXPECT_EQ(n, floor.DynamicCells());
  EXPECT_TRUE(Bit(first, 0));  // the corner is wall
}

// A slice of the floor is the same bits as the whole floor's, from any first cell.
TEST(OfficeFloor, ASliceIsTheWholeFloorsBitsFromItsFirstCell) {
  const OfficeFloor floor;
  const double t = kMonday + 2 * 24 * kHour + 10.5 * kHour;
  const std::string whole = floor.Occupied(0, OfficeFloor::kCells, t);
  for (uint64_t first : {uint64_t{0}, uint64_t{1}, uint64_t{7}, uint64_t{12345}, OfficeFloor::kCells - 9}) {
    for (uint64_t count : {uint64_t{1}, uint64_t{9}, uint64_t{8}, OfficeFloor::kCells / 3}) {
      if (first + count > OfficeFloor::kCells) continue;
      const std::string slice = floor.Occupied(first, count, t);
      ASSERT_EQ(slice.size(), (count + 7) / 8);
      for (uint64_t i = 0; i < count; ++i) ASSERT_EQ(Bit(slice, i), Bit(whole, first + i)) << first << " + " << i;
      for (uint64_t i = count; i < slice.size() * 8; ++i) ASSERT_FALSE(Bit(slice, i)) << "unused bit " << i;
    }
  }
}

// The office keeps hours: a weekday morning has its doors open (fewer occupied cells where they
// are) and people at their desks; a Sunday night has neither. The same seed gives the same floor.
TEST(OfficeFloor, KeepsOfficeHoursAndIsDeterministic) {
  const OfficeFloor floor(7), same(7), other(8);
  const double wednesday_11 = kMonday + 2 * 24 * kHour + 11 * kHour;
  const double sunday_3 = kMonday + 6 * 24 * kHour + 3 * kHour;
  const std::string day = floor.Occupied(0, OfficeFloor::kCells, wednesday_11);
  const std::string night = floor.Occupied(0, OfficeFloor::kCells, sunday_3);
  EXPECT_EQ(day, same.Occupied(0, OfficeFloor::kCells, wednesday_11));
  EXPECT_NE(Count(day), Count(night));
  // The door of the first room (x 28..43, the corridor's upper wall at y 168..169): open by day,
  // closed at night.
  const uint64_t door_cell = 30 + uint64_t{OfficeFloor::kWidth} * 168;
  EXPECT_FALSE(Bit(day, door_cell));
  EXPECT_TRUE(Bit(night, door_cell));
  // Another seed jitters the schedules, so some day differs.
  bool differs = false;
  for (double t = kMonday; t < kMonday + 7 * 24 * kHour && !differs; t += 600) {
    differs = floor.Occupied(0, OfficeFloor::kCells, t) != other.Occupied(0, OfficeFloor::kCells, t);
  }
  EXPECT_TRUE(differs);
}

}  // namespace
}  // namespace fremen::bench
