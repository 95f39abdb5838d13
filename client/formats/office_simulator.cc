// The simulated office (see office_simulator.h). The random numbers come from splitmix64 rather
// than <random>'s distributions, whose output differs between standard libraries: the demo must
// produce the same week everywhere.
#include "client/formats/office_simulator.h"

#include <cmath>

namespace fremen::formats {

namespace {

constexpr double kHour = 3600;
constexpr double kDay = 24 * kHour;

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  bool Chance(double p) { return Uniform() < p; }

 private:
  uint64_t state_;
};

// The desks: a person sits at (x, y) on weekdays, arriving and leaving around these hours.
struct Desk {
  uint32_t x, y;
  double arrive_hour, leave_hour;
};
constexpr Desk kDesks[] = {{5, 4, 8.5, 17.0},   {9, 4, 9.0, 18.0},  {5, 15, 8.0, 16.5},
                           {9, 15, 10.0, 19.0}, {30, 5, 8.5, 17.5}, {34, 14, 9.5, 18.5}};

// One day's plan, drawn once a day so that a day's behaviour is consistent.
struct DayPlan {
  double door_open_hour = 0, door_close_hour = 0;
  double desk_arrive[std::size(kDesks)] = {};
  double desk_leave[std::size(kDesks)] = {};
  bool desk_present[std::size(kDesks)] = {};
};

bool IsWeekday(int day_index) { return day_index % 7 < 5; }  // day 0 is a Monday

DayPlan PlanDay(SplitMix64& rng, int day_index) {
  DayPlan plan;
  plan.door_open_hour = 7.75 + rng.Uniform() * 0.75;  // 7:45 .. 8:30
  plan.door_close_hour = 17.5 + rng.Uniform() * 1.0;  // 17:30 .. 18:30
  for (size_t i = 0; i < std::size(kDesks); ++i) {
    plan.desk_present[i] = IsWeekday(day_index) && rng.Chance(0.85);
    plan.desk_arrive[i] = kDesks[i].arrive_hour + (rng.Uniform() - 0.5);
    plan.desk_leave[i] = kDesks[i].leave_hour + (rng.Uniform() - 0.5);
  }
  return plan;
}

bool DoorOpen(SplitMix64& rng, const DayPlan& plan, int day_index, double hour) {
  if (IsWeekday(day_index) && hour >= plan.door_open_hour && hour < plan.door_close_hour) {
    return !rng.Chance(0.05);  // now and then someone closes it for a call
  }
  return rng.Chance(0.02);  // a cleaner or a weekend visitor
}

bool MeetingRoomBusy(SplitMix64& rng, int day_index, double hour) {
  const int weekday = day_index % 7;
  if (weekday < 5 && hour >= 9.0 && hour < 9.25) return rng.Chance(0.9);  // daily stand-up
  if ((weekday == 1 || weekday == 3) && hour >= 14.0 && hour < 15.5) return rng.Chance(0.9);
  return rng.Chance(0.01);
}

bool KitchenLightOn(SplitMix64& rng, int day_index, double hour) {
  if (IsWeekday(day_index) && hour >= 11.75 && hour < 13.5) return rng.Chance(0.85);
  if (IsWeekday(day_index) && hour >= 8.0 && hour < 18.0) return rng.Chance(0.15);
  return rng.Chance(0.01);
}

}  // namespace

bool IsOfficeWall(uint32_t x, uint32_t y) {
  if (x == 0 || y == 0 || x == kOfficeWidth - 1 || y == kOfficeHeight - 1) return true;
  return x == kDoorX && (y < kDoorY0 || y > kDoorY1);
}

OfficeWeek SimulateOffice(const OfficeOptions& options) {
  SplitMix64 rng(options.seed);
  OfficeWeek week;
  const double end = options.start + options.days * kDay;
  int planned_day = -1;
  DayPlan plan;
  for (double t = options.start; t < end; t += options.scan_interval) {
    const double since = t - options.start;
    const int day_index = static_cast<int>(std::floor(since / kDay));
    const double hour = (since - day_index * kDay) / kHour;
    if (day_index != planned_day) {
      plan = PlanDay(rng, day_index);
      planned_day = day_index;
    }
    const bool door_open = DoorOpen(rng, plan, day_index, hour);

    NamedStateBatch states;
    states.time = t;
    states.names = {"door", "meeting-room", "kitchen-light"};
    states.values = {door_open ? 1.0f : 0.0f, MeetingRoomBusy(rng, day_index, hour) ? 1.0f : 0.0f,
                     KitchenLightOn(rng, day_index, hour) ? 1.0f : 0.0f};
    week.state_scans.push_back(std::move(states));

    // The grid: start from the static layout, then the door and the people.
    std::vector<float> occupied(kOfficeWidth * kOfficeHeight, 0.0f);
    for (uint32_t y = 0; y < kOfficeHeight; ++y) {
      for (uint32_t x = 0; x < kOfficeWidth; ++x) occupied[y * kOfficeWidth + x] = IsOfficeWall(x, y) ? 1.0f : 0.0f;
    }
    for (uint32_t y = kDoorY0; y <= kDoorY1; ++y) occupied[y * kOfficeWidth + kDoorX] = door_open ? 0.0f : 1.0f;
    for (size_t i = 0; i < std::size(kDesks); ++i) {
      const bool seated = plan.desk_present[i] && hour >= plan.desk_arrive[i] && hour < plan.desk_leave[i] &&
                          !rng.Chance(0.1);  // away for a coffee
      if (seated) occupied[kDesks[i].y * kOfficeWidth + kDesks[i].x] = 1.0f;
    }
    // People walking along the corridor (row 9-10, left of the partition) by day.
    if (IsWeekday(day_index) && hour >= 8.0 && hour < 18.0) {
      for (int walker = 0; walker < 2; ++walker) {
        if (!rng.Chance(0.5)) continue;
        const uint32_t x = 1 + static_cast<uint32_t>(rng.Uniform() * (kDoorX - 1));
        const uint32_t y = kDoorY0 + static_cast<uint32_t>(rng.Uniform() * 2);
        occupied[y * kOfficeWidth + x] = 1.0f;
      }
    }
    CellBatch scan;
    scan.time = t;
    for (uint32_t y = 0; y < kOfficeHeight; ++y) {
      for (uint32_t x = 0; x < kOfficeWidth; ++x) scan.Add(x, y, 0, occupied[y * kOfficeWidth + x]);
    }
    week.grid_scans.push_back(std::move(scan));
  }
  return week;
}

}  // namespace fremen::formats
