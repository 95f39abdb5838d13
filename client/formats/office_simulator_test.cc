#include "client/formats/office_simulator.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fremen::formats {
namespace {

constexpr double kHour = 3600;

TEST(OfficeSimulatorTest, AWeekOfScansOfEveryCellAndState) {
  const OfficeOptions options;
  const OfficeWeek week = SimulateOffice(options);
  ASSERT_EQ(week.grid_scans.size(), 7u * 24 * 6);
  ASSERT_EQ(week.state_scans.size(), week.grid_scans.size());
  EXPECT_EQ(week.grid_scans[0].time, options.start);
  EXPECT_EQ(week.grid_scans[1].time, options.start + 600);
  EXPECT_EQ(week.grid_scans[0].size(), kOfficeWidth * kOfficeHeight);
  EXPECT_EQ(week.state_scans[0].names, (std::vector<std::string>{"door", "meeting-room", "kitchen-light"}));
}

TEST(OfficeSimulatorTest, SameSeedSameWeekOtherSeedOtherWeek) {
  const OfficeWeek a = SimulateOffice({});
  const OfficeWeek b = SimulateOffice({});
  OfficeOptions other;
  other.seed = 2;
  const OfficeWeek c = SimulateOffice(other);
  bool grid_differs = false, states_differ = false;
  for (size_t i = 0; i < a.grid_scans.size(); ++i) {
    ASSERT_EQ(a.grid_scans[i].values, b.grid_scans[i].values);
    ASSERT_EQ(a.state_scans[i].values, b.state_scans[i].values);
    grid_differs |= a.grid_scans[i].values != c.grid_scans[i].values;
    states_differ |= a.state_scans[i].values != c.state_scans[i].values;
  }
  EXPECT_TRUE(grid_differs);
  EXPECT_TRUE(states_differ);
}

TEST(OfficeSimulatorTest, DoorFollowsWorkingHoursAndWallsNeverMove) {
  const OfficeOptions options;
  const OfficeWeek week = SimulateOffice(options);
  int work_open = 0, work = 0, night_open = 0, night = 0;
  for (size_t i = 0; i < week.state_scans.size(); ++i) {
    const NamedStateBatch& scan = week.state_scans[i];
    const double since = scan.time - options.start;
    const int day = static_cast<int>(since / 86400);
    const double hour = std::fmod(since, 86400) / kHour;
    const bool door_open = scan.values[0] == 1.0f;
    if (day < 5 && hour >= 9 && hour < 17) {
      ++work;
      work_open += door_open;
    } else if (hour < 6 || hour >= 21 || day >= 5) {
      ++night;
      night_open += door_open;
    }
    // The doorway cells of the grid agree with the door state.
    const CellBatch& grid = week.grid_scans[i];
    EXPECT_EQ(grid.values[kDoorY0 * kOfficeWidth + kDoorX], door_open ? 0.0f : 1.0f);
    for (size_t c = 0; c < grid.size(); ++c) {
      if (IsOfficeWall(grid.x[c], grid.y[c])) {
        ASSERT_EQ(grid.values[c], 1.0f) << grid.x[c] << "," << grid.y[c];
      }
    }
  }
  EXPECT_GT(work_open, work * 8 / 10);
  EXPECT_LT(night_open, night / 10);
}

}  // namespace
}  // namespace fremen::formats
