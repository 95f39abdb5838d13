// `fremenctl ingest`: reads one input (formats in client/formats), creates the map on request,
// sends the batches through a MapWriter and prints what the daemon accepted.
#include "client/fremenctl/ingest_command.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/formats/grid_csv.h"
#include "client/formats/map_server_snapshots.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/map_writer.h"
#include "client/fremenctl/offline_eval.h"
#include "client/lib/history_builder.h"

namespace fremen::client {

namespace {

constexpr char kCommand[] = "ingest";

struct IngestArgs {
  std::string map;
  std::string states_file;
  std::string state_name;
  uint64_t state_id = 0;
  std::string csv_file;
  std::string map_server_dir;
  std::string times_file;
  bool create = false;
  double resolution = 1.0;
  bool update = false;
  size_t batch_cells = 100'000;
};

v1::Map NewMap(const std::string& name, v1::MapKind kind) {
  v1::Map map;
  map.set_name(name);
  map.set_kind(kind);
  return map;
}

formats::GridPlacement PlacementOf(const v1::Map& map) {
  const v1::GridGeometry& g = map.grid();
  return {g.resolution(), g.origin().x(), g.origin().y(), g.size().x(), g.size().y()};
}

// The grid map named by args, created on request with `geometry` when missing.
v1::Map GridMap(const Client& client, const IngestArgs& args, const v1::GridGeometry& geometry) {
  if (args.create) {
    v1::Map map = NewMap(args.map, v1::MAP_KIND_GRID);
    *map.mutable_grid() = geometry;
    return CreateMapIfMissing(client, map, kCommand);
  }
  absl::StatusOr<v1::Map> map = client.GetMap(args.map, GlobalCall());
  if (!map.ok()) FailCall(kCommand, "cannot read the map", map.status(), args.map);
  if (map->kind() != v1::MAP_KIND_GRID) {
    FailInput(kCommand, absl::FailedPreconditionError(absl::StrCat(
                            "map ", args.map, " is a generic map; --csv and --map-server need a grid map")));
  }
  return *map;
}

void IngestStates(const Client& client, const IngestArgs& args) {
  if (args.state_name.empty() == (args.state_id == 0)) {
    FailUsage(kCommand, "--states needs the state: --name NAME or --id ID (one of them)");
  }
  absl::StatusOr<std::vector<model::Observation>> observations = ReadObservations(args.states_file);
  if (!observations.ok()) FailInput(kCommand, observations.status());
  if (args.create) {
    CreateMapIfMissing(client, NewMap(args.map, v1::MAP_KIND_GENERIC), kCommand);
  }
  MapWriter writer(client, args.map, kCommand);
  // The file's observations as histories (a time per observation), many per batch: one batch per
  // line took a log record and an acknowledgement per observation. In file order, which the
  // daemon keeps, so a file in time order gives the model of a robot that streamed it.
  HistoryBuilder history =
      args.state_name.empty() ? HistoryBuilder::ForId(args.state_id) : HistoryBuilder::ForName(args.state_name);
  for (const model::Observation& o : *observations) {
    history.Add(o.t, static_cast<float>(o.s));
    if (history.size() == kHistoryBatchObservations) writer.SendScan(history.Build());
  }
  if (history.size() > 0) writer.SendScan(history.Build());
  const IngestTotals totals = writer.Finish();
  std::printf("ingested %s into %s: %s\n", args.states_file.c_str(), args.map.c_str(),
              MapWriter::Summary(totals, writer.first_rejections()).c_str());
}

void IngestCsv(const Client& client, const IngestArgs& args) {
  absl::StatusOr<std::vector<formats::CellObservation>> rows = formats::ReadGridCsv(args.csv_file);
  if (!rows.ok()) FailInput(kCommand, rows.status());
  // A grid just large enough for every cell of the file, when it has to be created.
  v1::GridGeometry geometry;
  geometry.set_resolution(args.resolution);
  uint32_t max_x = 0, max_y = 0, max_z = 0;
  for (const formats::CellObservation& o : *rows) {
    max_x = std::max(max_x, o.x);
    max_y = std::max(max_y, o.y);
    max_z = std::max(max_z, o.z);
  }
  geometry.mutable_size()->set_x(max_x + 1);
  geometry.mutable_size()->set_y(max_y + 1);
  geometry.mutable_size()->set_z(max_z + 1);
  GridMap(client, args, geometry);
  MapWriter writer(client, args.map, kCommand);
  for (const formats::CellBatch& batch : formats::GroupByTime(*rows)) writer.Send(batch);
  const IngestTotals totals = writer.Finish();
  std::printf("ingested %s into %s: %s\n", args.csv_file.c_str(), args.map.c_str(),
              MapWriter::Summary(totals, writer.first_rejections()).c_str());
}

// Two passes over the snapshots, so that memory holds one image at a time: the first reads and
// checks every file against the map's grid (a bad file must not leave half a directory behind,
// nor an empty new map), the second reads them again and sends them.
void IngestMapServer(const Client& client, const IngestArgs& args) {
  absl::StatusOr<std::vector<formats::SnapshotFile>> files =
      formats::ListSnapshots(args.map_server_dir, args.times_file);
  if (!files.ok()) FailInput(kCommand, files.status());
  const auto read = [&](size_t i) {
    absl::StatusOr<formats::Snapshot> snapshot = formats::ReadSnapshot((*files)[i].yaml_path);
    if (!snapshot.ok()) FailInput(kCommand, snapshot.status());
    return *std::move(snapshot);
  };

  // The map's grid, or the first snapshot's for a map --create makes.
  v1::Map map;
  absl::StatusOr<v1::Map> existing = client.GetMap(args.map, GlobalCall());
  if (existing.ok()) {
    map = *existing;
  } else if (existing.status().code() == absl::StatusCode::kNotFound && args.create) {
    const formats::Snapshot first = read(0);
    map = NewMap(args.map, v1::MAP_KIND_GRID);
    v1::GridGeometry& geometry = *map.mutable_grid();
    geometry.set_resolution(first.metadata.resolution);
    geometry.mutable_origin()->set_x(first.metadata.origin_x);
    geometry.mutable_origin()->set_y(first.metadata.origin_y);
    geometry.mutable_size()->set_x(static_cast<uint32_t>(first.image.width));
    geometry.mutable_size()->set_y(static_cast<uint32_t>(first.image.height));
    geometry.mutable_size()->set_z(1);
  } else {
    FailCall(kCommand, "cannot read the map", existing.status(), args.map);
  }
  if (map.kind() != v1::MAP_KIND_GRID) {
    FailInput(kCommand, absl::FailedPreconditionError(
                            absl::StrCat("map ", args.map, " is a generic map; --map-server needs a grid map")));
  }
  const formats::GridPlacement grid = PlacementOf(map);
  std::vector<std::pair<uint32_t, uint32_t>> offsets(files->size());
  for (size_t i = 0; i < files->size(); ++i) {
    absl::Status placed =
        formats::PlaceSnapshot(read(i), grid, (*files)[i].yaml_path, offsets[i].first, offsets[i].second);
    if (!placed.ok()) FailInput(kCommand, placed);
  }
  if (!existing.ok()) CreateMapIfMissing(client, map, kCommand);

  MapWriter writer(client, args.map, kCommand);
  for (size_t i = 0; i < files->size(); ++i) {
    for (const formats::CellBatch& batch :
         formats::SnapshotBatches(read(i), (*files)[i].time, offsets[i].first, offsets[i].second, args.batch_cells)) {
      writer.Send(batch);
    }
  }
  const IngestTotals totals = writer.Finish();
  std::printf("ingested %zu map_server snapshots from %s into %s: %s\n", files->size(), args.map_server_dir.c_str(),
              args.map.c_str(), MapWriter::Summary(totals, writer.first_rejections()).c_str());
}

void RunIngest(const IngestArgs& args) {
  const int inputs = !args.states_file.empty() + !args.csv_file.empty() + !args.map_server_dir.empty();
  if (inputs != 1) FailUsage(kCommand, "give exactly one input: --states FILE, --csv FILE or --map-server DIR");
  if (!args.times_file.empty() && args.map_server_dir.empty()) FailUsage(kCommand, "--times goes with --map-server");
  const Client client = ConnectOrExit(kCommand);
  if (!args.states_file.empty()) {
    IngestStates(client, args);
  } else if (!args.csv_file.empty()) {
    IngestCsv(client, args);
  } else {
    IngestMapServer(client, args);
  }
  if (args.update) {
    const uint64_t published = RunUpdateAndWait(client, args.map, kCommand);
    std::printf("update of %s: %llu states published\n", args.map.c_str(), static_cast<unsigned long long>(published));
  }
}

}  // namespace

void RegisterIngestCommand(CLI::App& app) {
  auto args = std::make_shared<IngestArgs>();
  CLI::App* cmd = app.add_subcommand("ingest", "Send observations from files into a map");
  cmd->add_option("--map", args->map, "The map to write")->required()->type_name("MAP");
  CLI::Option* states =
      cmd->add_option("--states", args->states_file, "One generic state's `time state` file (seconds, state in [0, 1])")
          ->type_name("FILE");
  cmd->add_option("--name", args->state_name, "With --states: the state's name (created on first sight)")
      ->type_name("NAME");
  cmd->add_option("--id", args->state_id, "With --states: the state's 64-bit id instead of a name")
      ->type_name("ID")
      ->check(CLI::PositiveNumber);
  CLI::Option* csv =
      cmd->add_option("--csv", args->csv_file, "Grid observations, CSV time,x,y[,z],state (cell indices)")
          ->type_name("FILE");
  CLI::Option* map_server = cmd->add_option("--map-server", args->map_server_dir,
                                            "A directory of ROS map_server snapshots, PGM + YAML per time")
                                ->type_name("DIR");
  states->excludes(csv)->excludes(map_server);
  csv->excludes(map_server);
  cmd->add_option("--times", args->times_file,
                  "With --map-server: `FILE.yaml TIME` lines instead of times in file names")
      ->type_name("FILE");
  cmd->add_flag("--create", args->create, "Create the map when it does not exist (see below)");
  cmd->add_option("--resolution", args->resolution, "With --csv --create: the new grid's cell size, metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--batch-cells", args->batch_cells, "Most observations per batch of a map_server snapshot")
      ->check(CLI::Range(1, 1'000'000))
      ->capture_default_str();
  cmd->add_flag("--update", args->update,
                "Run the map's update job after ingesting, and wait (the first update publishes P; the\n"
                "observations after it score each order, so a later update selects the best one)");
  cmd->footer(
      "Inputs (exactly one):\n"
      "  --states FILE   one observation per line, `time state` separated by blanks; '#' comments.\n"
      "                  Every line is one batch of the state named by --name (or --id); generic maps.\n"
      "  --csv FILE      one observation per line, time,x,y,state or time,x,y,z,state; an optional\n"
      "                  header line time,x,y[,z],state; '#' comments. One batch per distinct time.\n"
      "  --map-server DIR  ROS map_server maps, one per time: every *.yaml of DIR names its PGM image\n"
      "                  (image, resolution, origin [x, y, 0], negate, occupied_thresh, free_thresh,\n"
      "                  mode trinary|scale). The time is the number that ends the YAML's name\n"
      "                  (office_1700000000.yaml, 1700000000.5.yaml), or comes from --times FILE whose\n"
      "                  lines are `NAME.yaml TIME` (names relative to DIR; only listed files are read).\n"
      "                  Pixels become observations as map_server loads them: occupied 1, free 0,\n"
      "                  scale mode's in-between cells as soft observations, unknown cells skipped.\n"
      "                  The snapshot's origin must sit on a cell corner of the map's grid, at its\n"
      "                  resolution, with the whole image inside the grid.\n"
      "--create makes a missing map: generic for --states; for --csv a grid just large enough for\n"
      "the file's cells at --resolution with origin (0, 0, 0); for --map-server the first snapshot's\n"
      "grid. Every file is read and checked before anything is sent (or a map created).\n"
      "Exit codes: 0 success, 1 bad input (the message names file:line and the field) or the daemon\n"
      "refused, 2 bad usage.\n"
      "\n"
      "Examples:\n"
      "  fremenctl ingest --map lab --states door.txt --name door --create\n"
      "  fremenctl ingest --map office --map-server snapshots/ --create --update");
  cmd->callback([args] { RunIngest(*args); });
}

}  // namespace fremen::client
