// `fremenctl demo`: creates PREFIX-office (grid) and PREFIX-states (generic), ingests the simulated
// days, runs the update of both and prints commands to try.
#include "client/fremenctl/demo_command.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "client/formats/office_simulator.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/map_writer.h"

namespace fremen::client {

namespace {

constexpr char kCommand[] = "demo";
constexpr double kDay = 86400;

struct DemoArgs {
  std::string prefix = "demo";
  uint64_t seed = 1;
  double days = 7;
  bool replace = false;
};

// Creates `map`, first deleting a map of that name with --replace; without it an existing map
// ends the command (the demo never overwrites data by surprise).
void CreateFresh(const Client& client, const v1::Map& map, bool replace) {
  absl::StatusOr<v1::Map> existing = client.GetMap(map.name(), GlobalCall());
  if (existing.ok()) {
    if (!replace) {
      FailInput(kCommand,
                absl::AlreadyExistsError(absl::StrCat("map ", map.name(),
                                                      " already exists; pass --replace to delete and recreate it, or "
                                                      "choose another --prefix")));
    }
    if (absl::Status deleted = client.DeleteMap(map.name(), GlobalCall()); !deleted.ok()) {
      FailCall(kCommand, "cannot delete the old map", deleted, map.name());
    }
  } else if (existing.status().code() != absl::StatusCode::kNotFound) {
    FailCall(kCommand, "cannot read the map", existing.status(), map.name());
  }
  absl::StatusOr<v1::Map> created = client.CreateMap(map, GlobalCall());
  if (!created.ok()) FailCall(kCommand, "cannot create the map", created.status(), map.name());
}

std::string Rfc3339(double t) {
  return absl::FormatTime("%Y-%m-%dT%H:%M:%SZ", absl::FromUnixSeconds(static_cast<int64_t>(t)), absl::UTCTimeZone());
}

void RunDemo(const DemoArgs& args) {
  const std::string office = args.prefix + "-office";
  const std::string states = args.prefix + "-states";
  const Client client = ConnectOrExit(kCommand);

  v1::Map grid;
  grid.set_name(office);
  grid.set_kind(v1::MAP_KIND_GRID);
  grid.mutable_grid()->set_resolution(formats::kOfficeResolution);
  grid.mutable_grid()->mutable_size()->set_x(formats::kOfficeWidth);
  grid.mutable_grid()->mutable_size()->set_y(formats::kOfficeHeight);
  grid.mutable_grid()->mutable_size()->set_z(1);
  v1::Map generic;
  generic.set_name(states);
  generic.set_kind(v1::MAP_KIND_GENERIC);
  CreateFresh(client, grid, args.replace);
  CreateFresh(client, generic, args.replace);

  formats::OfficeOptions options;
  options.seed = args.seed;
  options.days = args.days;
  const formats::OfficeWeek week = formats::SimulateOffice(options);
  std::printf("simulated %g days of an office from %s (a Monday), a scan every %g minutes\n", args.days,
              Rfc3339(options.start).c_str(), options.scan_interval / 60);
  // Day by day, with the update after each day as fremend's nightly job would run it: the first
  // update publishes P, the next days' observations score every order, later updates select.
  MapWriter office_writer(client, office, kCommand);
  MapWriter states_writer(client, states, kCommand);
  size_t next = 0;
  int updates = 0;
  for (double day_end = options.start + kDay; next < week.grid_scans.size(); day_end += kDay) {
    for (; next < week.grid_scans.size() && week.grid_scans[next].time < day_end; ++next) {
      office_writer.Send(week.grid_scans[next]);
      states_writer.Send(week.state_scans[next]);
    }
    // The update must see the day's batches: wait for their acks first.
    office_writer.Flush();
    states_writer.Flush();
    RunUpdateAndWait(client, office, kCommand);
    RunUpdateAndWait(client, states, kCommand);
    ++updates;
  }
  const IngestTotals office_totals = office_writer.Finish();
  const IngestTotals states_totals = states_writer.Finish();
  std::printf("%s (grid %u x %u cells of %g m): %s\n", office.c_str(), formats::kOfficeWidth, formats::kOfficeHeight,
              formats::kOfficeResolution, MapWriter::Summary(office_totals, office_writer.first_rejections()).c_str());
  std::printf("%s (door, meeting-room, kitchen-light): %s\n", states.c_str(),
              MapWriter::Summary(states_totals, states_writer.first_rejections()).c_str());
  std::printf("%d updates of both maps, one after each simulated day\n", updates);

  // Suggestions at times after the simulated span: the next 09:00 and 03:00 (UTC).
  const double midnight = options.start + std::ceil(args.days) * kDay;
  const double morning = midnight + 9 * 3600, afternoon = midnight + 14 * 3600, night = midnight + 3 * 3600;
  std::printf(
      "\nNext, try:\n"
      "  fremenctl model --map %s --name door --plot door.svg\n"
      "      the door's model and a picture of a week of p(t)\n"
      "  fremenctl predict --map %s --name door --name meeting-room --time %s --time %s\n"
      "      will the door be open and the meeting room busy at 09:00 and at 14:00?\n"
      "  fremenctl region --map %s --time %s --out morning\n"
      "      the predicted office at 09:00 after the simulated days: morning.pgm/.yaml (map_server) and morning.png\n"
      "  fremenctl region --map %s --time %s --out night\n"
      "      the same at 03:00: the door is closed (its doorway cells at x = %u are occupied)\n"
      "  fremenctl model --map %s --cell %u,%u\n"
      "      the doorway cell's model: its periods, the error of each order, persistence\n",
      states.c_str(), states.c_str(), Rfc3339(morning).c_str(), Rfc3339(afternoon).c_str(), office.c_str(),
      Rfc3339(morning).c_str(), office.c_str(), Rfc3339(night).c_str(), formats::kDoorX, office.c_str(),
      formats::kDoorX, formats::kDoorY0);
}

}  // namespace

void RegisterDemoCommand(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand("demo", "Simulate a week of an office into fremend, to have maps to look at");
  cmd->add_option("--prefix", args->prefix, "Names the maps PREFIX-office (grid) and PREFIX-states (generic)")
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Same seed, same week")->capture_default_str();
  cmd->add_option("--days", args->days, "Days simulated")->check(CLI::Range(0.1, 365.0))->capture_default_str();
  cmd->add_flag("--replace", args->replace, "Delete and recreate the demo maps when they exist");
  cmd->footer(
      "The office (10 m x 5 m, 40 x 20 cells of 0.25 m) has walls all round and a partition whose\n"
      "doorway is the office door: open on weekdays from about 08:00 to 18:00 (UTC), seldom at other\n"
      "times. Six desks are occupied in working hours, people walk the corridor by day. The generic map\n"
      "holds the door, a meeting room (daily stand-up at 09:00, meetings Tue/Thu 14:00-15:30) and a\n"
      "kitchen light (lunch). A robot scans everything every 10 minutes from Monday 20 Nov 2023.\n"
      "Both maps are updated after each simulated day, as fremend's nightly job would.\n"
      "Exit codes: 0 success, 1 the maps exist (use --replace) or the daemon failed, 2 bad usage.");
  cmd->callback([args] { RunDemo(*args); });
}

}  // namespace fremen::client
