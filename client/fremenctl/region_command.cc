// `fremenctl region`: PredictRegion of one z-plane of a box, written by formats/region_export.
#include "client/fremenctl/region_command.h"

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "client/formats/occupancy_pixels.h"
#include "client/formats/region_export.h"
#include "client/fremenctl/cli_args.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/map_writer.h"

namespace fremen::client {

namespace {

constexpr char kCommand[] = "region";

struct RegionArgs {
  std::string map;
  std::string time;
  std::string out;
  std::vector<uint32_t> box;  // x0 y0 x1 y1
  uint32_t z = 0;
  std::string mode = "trinary";
  bool persistence = false;
  std::optional<uint32_t> order;
};

void RunRegion(const RegionArgs& args) {
  absl::StatusOr<double> time = ParseTimeArg(args.time);
  if (!time.ok()) FailUsage(kCommand, absl::StrCat("--time: ", time.status().message()));
  if (!args.box.empty() && args.box.size() != 4) FailUsage(kCommand, "--box takes four numbers: X0 Y0 X1 Y1");
  const formats::MapMode mode = args.mode == "scale" ? formats::MapMode::kScale : formats::MapMode::kTrinary;

  const Client client = ConnectOrExit(kCommand);
  absl::StatusOr<v1::Map> map = client.GetMap(args.map, GlobalCall());
  if (!map.ok()) FailCall(kCommand, "cannot read the map", map.status(), args.map);
  if (map->kind() != v1::MAP_KIND_GRID) {
    FailInput(kCommand, absl::FailedPreconditionError(absl::StrCat("map ", args.map, " is not a grid map")));
  }
  const v1::GridGeometry& grid = map->grid();
  RegionQuery query;
  query.lo = {0, 0, args.z};
  query.hi = {grid.size().x(), grid.size().y(), args.z + 1};
  if (!args.box.empty()) {
    query.lo.x = args.box[0];
    query.lo.y = args.box[1];
    query.hi.x = args.box[2];
    query.hi.y = args.box[3];
  }
  query.time = *time;
  query.model.persistence = args.persistence;
  query.model.order = args.order;
  query.output = v1::REGION_OUTPUT_FLOAT;
  absl::StatusOr<RegionArray> region = client.PredictRegion(args.map, query, GlobalCall());
  if (!region.ok()) FailCall(kCommand, "cannot predict the region", region.status(), args.map);

  formats::ProbabilityPlane plane;
  plane.width = region->shape.x;
  plane.height = region->shape.y;
  plane.p = region->floats;
  plane.resolution = grid.resolution();
  plane.origin_x = grid.origin().x() + query.lo.x * grid.resolution();
  plane.origin_y = grid.origin().y() + query.lo.y * grid.resolution();
  if (absl::Status written = formats::WriteRegionFiles(args.out, plane, mode); !written.ok()) {
    FailInput(kCommand, written);
  }
  // Counted as the trinary PGM classifies the cells.
  const formats::MapMetadata trinary = formats::ExportMetadata(plane, "", formats::MapMode::kTrinary);
  size_t occupied = 0, free = 0;
  for (float p : plane.p) {
    const uint8_t pixel = formats::PixelFromProbability(p, trinary);
    occupied += pixel == formats::kPixelOccupied;
    free += pixel == formats::kPixelFree;
  }
  std::printf("wrote %s.pgm, %s.yaml and %s.png: %u x %u cells at t = %.3f (%zu occupied, %zu free, %zu unknown)\n",
              args.out.c_str(), args.out.c_str(), args.out.c_str(), plane.width, plane.height, *time, occupied, free,
              plane.p.size() - occupied - free);
}

}  // namespace

void RegisterRegionCommand(CLI::App& app) {
  auto args = std::make_shared<RegionArgs>();
  CLI::App* cmd = app.add_subcommand("region", "Export the predicted map of a grid at a time (PGM + YAML, PNG)");
  cmd->add_option("--map", args->map, "A grid map")->required()->type_name("MAP");
  cmd->add_option("--time", args->time, "When: seconds since the epoch, RFC 3339 or \"now\"")
      ->required()
      ->type_name("TIME");
  cmd->add_option("--out", args->out, "Writes PREFIX.pgm, PREFIX.yaml and PREFIX.png")->required()->type_name("PREFIX");
  cmd->add_option("--box", args->box, "Cells [X0, X1) x [Y0, Y1); default: the whole grid")
      ->expected(4)
      ->type_name("X0 Y0 X1 Y1");
  cmd->add_option("--z", args->z, "The z-plane of a 3-D grid")->capture_default_str();
  cmd->add_option("--mode", args->mode, "map_server mode of the PGM: trinary (occupied/free/unknown) or scale")
      ->check(CLI::IsMember({"trinary", "scale"}))
      ->capture_default_str();
  cmd->add_flag("--persistence", args->persistence, "Blend in each cell's last observation (persistence model)");
  cmd->add_option("--order", args->order, "Evaluate every cell at this model order instead of its selected one");
  cmd->footer(
      "The PGM + YAML pair loads in ROS map_server / nav2 as the map at --time: a cell is occupied\n"
      "(pixel 0) when p >= 0.65, free (254) when p <= 0.196, unknown (205) in between — never-observed\n"
      "cells predict 0.5 and so are unknown. The YAML carries the box's origin and the grid's\n"
      "resolution, with map_saver's thresholds (occupied_thresh 0.65, free_thresh 0.196). --mode scale\n"
      "writes gray (100 - 100p)% instead. The PNG is a picture of p: white free, black occupied.\n"
      "Exit codes: 0 success, 1 the daemon refused or a file could not be written, 2 bad usage.\n"
      "\n"
      "Example, tomorrow morning's map of an office:\n"
      "  fremenctl region --map office --time 2026-11-23T09:00:00Z --out monday-9am");
  cmd->callback([args] { RunRegion(*args); });
}

}  // namespace fremen::client
