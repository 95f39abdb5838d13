// `fremenctl maps`: create (every setting of a map as an option), list (a table, page by page from
// the daemon; of every daemon of a fleet with several --address), get (key: value lines or
// --json) and delete (only with --yes: it removes the data).
#include "client/fremenctl/maps_command.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/fleet_maps.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

struct CreateArgs {
  std::string name;
  bool generic = false;
  double resolution = 0;
  std::vector<uint32_t> size;
  std::vector<double> origin;
  std::optional<uint32_t> max_order;
  bool no_persistence = false;
  std::optional<double> longest_period;
  std::optional<uint32_t> period_count;
  std::optional<double> half_life;
  std::string criterion;
  std::string order_selection;
  std::optional<double> order_margin;
  std::optional<double> order_temperature;
  double lossless_sampling = 0;
  uint32_t shards = 0;
};

std::string KindName(v1::MapKind kind) {
  switch (kind) {
    case v1::MAP_KIND_GRID:
      return "grid";
    case v1::MAP_KIND_GENERIC:
      return "generic";
    default:
      return "?";
  }
}

// "40×30×1 cells of 0.05 m" or "generic".
std::string Shape(const v1::Map& map) {
  if (map.kind() != v1::MAP_KIND_GRID) return KindName(map.kind());
  const v1::GridGeometry& g = map.grid();
  return absl::StrFormat("grid %ux%ux%u cells of %g m", g.size().x(), g.size().y(), std::max(1u, g.size().z()),
                         g.resolution());
}

void PrintMap(const v1::Map& map) {
  std::printf("name: %s\n", map.name().c_str());
  std::printf("kind: %s\n", KindName(map.kind()).c_str());
  if (map.kind() == v1::MAP_KIND_GRID) {
    const v1::GridGeometry& g = map.grid();
    std::printf("resolution: %g m\n", g.resolution());
    std::printf("size: %u %u %u cells\n", g.size().x(), g.size().y(), std::max(1u, g.size().z()));
    std::printf("origin: %g %g %g m\n", g.origin().x(), g.origin().y(), g.origin().z());
  }
  if (map.periods().explicit_seconds_size() > 0) {
    std::printf("periods: %s s\n", absl::StrJoin(map.periods().explicit_seconds(), " ").c_str());
  } else {
    std::printf("periods: %u harmonics of %g s%s\n", map.periods().count(), map.periods().longest_seconds(),
                map.periods().floor_periods() ? " (floored)" : "");
  }
  std::printf("max_order: %u\n", map.max_order());
  std::printf("persistence: %s\n", map.persistence() ? "on" : "off");
  std::printf("error_half_life: %g s\n", map.error_half_life_seconds());
  std::printf("criterion: %s\n", map.criterion() == v1::ERROR_CRITERION_SQUARED ? "squared" : "threshold");
  switch (map.order_selection()) {
    case v1::ORDER_SELECTION_MARGIN: std::printf("order_selection: margin %g\n", map.order_margin()); break;
    case v1::ORDER_SELECTION_PAPER: std::printf("order_selection: paper\n"); break;
    default: std::printf("order_selection: weighted, temperature %g\n", map.order_temperature()); break;
  }
  if (map.lossless_sampling_seconds() > 0) {
    std::printf("lossless: every %g s from %g\n", map.lossless_sampling_seconds(), map.lossless_origin());
  } else {
    std::printf("lossless: off\n");
  }
  std::printf("shards: %u\n", map.shards());
  std::printf("created: %s\n", FormatTimestamp(map.create_time()).c_str());
}

v1::Map MapOf(const CreateArgs& a) {
  v1::Map map;
  map.set_name(a.name);
  map.set_kind(a.generic ? v1::MAP_KIND_GENERIC : v1::MAP_KIND_GRID);
  if (!a.generic) {
    if (a.resolution <= 0 || a.size.empty()) {
      FailUsage("maps create",
                "a grid map needs --resolution METRES and --size X Y [Z] (or --generic for a map of "
                "named states)");
    }
    map.mutable_grid()->set_resolution(a.resolution);
    map.mutable_grid()->mutable_size()->set_x(a.size[0]);
    map.mutable_grid()->mutable_size()->set_y(a.size[1]);
    if (a.size.size() == 3) map.mutable_grid()->mutable_size()->set_z(a.size[2]);
    if (!a.origin.empty()) {
      map.mutable_grid()->mutable_origin()->set_x(a.origin[0]);
      map.mutable_grid()->mutable_origin()->set_y(a.origin[1]);
      if (a.origin.size() == 3) map.mutable_grid()->mutable_origin()->set_z(a.origin[2]);
    }
  } else if (a.resolution > 0 || !a.size.empty() || !a.origin.empty()) {
    FailUsage("maps create", "--resolution, --size and --origin are for grid maps; drop them or --generic");
  }
  if (a.max_order) map.set_max_order(*a.max_order);
  if (a.no_persistence) map.set_persistence(false);
  if (a.longest_period) map.mutable_periods()->set_longest_seconds(*a.longest_period);
  if (a.period_count) map.mutable_periods()->set_count(*a.period_count);
  if (a.half_life) map.set_error_half_life_seconds(*a.half_life);
  if (a.criterion == "squared") map.set_criterion(v1::ERROR_CRITERION_SQUARED);
  if (a.criterion == "threshold") map.set_criterion(v1::ERROR_CRITERION_THRESHOLD);
  if (a.order_selection == "margin") map.set_order_selection(v1::ORDER_SELECTION_MARGIN);
  if (a.order_selection == "paper") map.set_order_selection(v1::ORDER_SELECTION_PAPER);
  if (a.order_selection == "weighted") map.set_order_selection(v1::ORDER_SELECTION_WEIGHTED);
  if (a.order_margin) map.set_order_margin(*a.order_margin);
  if (a.order_temperature) map.set_order_temperature(*a.order_temperature);
  map.set_lossless_sampling_seconds(a.lossless_sampling);
  map.set_shards(a.shards);
  return map;
}

void RegisterCreate(CLI::App& maps) {
  auto a = std::make_shared<CreateArgs>();
  CLI::App* create = maps.add_subcommand("create", "Create a map (its settings are fixed from then on)");
  create->add_option("name", a->name, "the map's name: 1..128 of [A-Za-z0-9._-]")->required();
  create->add_flag("--generic", a->generic, "a map of generic states (doors, edges) instead of a grid");
  create->add_option("--resolution", a->resolution, "grid: cell edge, metres")->check(CLI::PositiveNumber);
  create->add_option("--size", a->size, "grid: cells along x y [z]")->expected(2, 3);
  create->add_option("--origin", a->origin, "grid: metric position of cell (0,0,0)'s corner: x y [z]")->expected(2, 3);
  create->add_option("--max-order", a->max_order, "highest model order L (default 5)")->check(CLI::Range(0, 64));
  create->add_flag("--no-persistence", a->no_persistence, "do not keep the persistence model");
  create->add_option("--longest-period", a->longest_period, "longest modelled period, seconds (default a week)")
      ->check(CLI::PositiveNumber);
  create->add_option("--periods", a->period_count, "number of harmonics of the longest period (default 24)")
      ->check(CLI::PositiveNumber);
  create->add_option("--half-life", a->half_life, "half-life of the order errors, seconds (default 7 days)")
      ->check(CLI::NonNegativeNumber);
  create->add_option("--criterion", a->criterion, "order-selection error: threshold (default) or squared")
      ->check(CLI::IsMember({"threshold", "squared"}));
  create->add_option("--order-selection", a->order_selection,
                     "how the order is chosen from the decayed errors: margin (default; a higher order must "
                     "win by --order-margin), weighted (the mean order of exp(-(r - r_min)/T) weights) or "
                     "paper (the exact minimum)")
      ->check(CLI::IsMember({"weighted", "margin", "paper"}));
  create->add_option("--order-margin", a->order_margin, "margin rule: how much a higher order must win by (0.001)")
      ->check(CLI::NonNegativeNumber);
  create->add_option("--order-temperature", a->order_temperature, "weighted rule: the temperature T (0.01)")
      ->check(CLI::PositiveNumber);
  create->add_option("--lossless-sampling", a->lossless_sampling, "keep lossless history sampled every S seconds")
      ->check(CLI::NonNegativeNumber);
  create->add_option("--shards", a->shards, "LMDB shards, 1..256 (default: the daemon's)")->check(CLI::Range(0, 256));
  create->callback([a] {
    Client client = ConnectOrExit("maps create");
    auto created = client.CreateMap(MapOf(*a), GlobalCall());
    if (!created.ok()) {
      if (absl::IsAlreadyExists(created.status())) {
        FailCall(
            "maps create", a->name,
            absl::AlreadyExistsError(absl::StrCat(
                created.status().message(), "; pick another name, or `fremenctl maps delete ", a->name, " --yes`")));
      }
      FailCall("maps create", a->name, created.status());
    }
    std::printf("created map %s: %s\n", created->name().c_str(), Shape(*created).c_str());
  });
}

// `maps list --address A,B,C`: every daemon's maps, merged in name order; a map that several
// daemons hold is on one line per daemon, marked DUPLICATE.
void ListFleet(bool json) {
  const FleetMaps fleet = ListFleetOrReport("maps list", ConnectFleetOrExit("maps list"));
  if (!json) std::printf("%-32s %-28s %-40s %s\n", "NAME", "DAEMON", "SHAPE", "CREATED");
  for (const FleetMap& held : fleet.maps) {
    if (json) {
      std::printf("{\"daemon\":\"%s\",\"duplicate\":%s,\"map\":%s}\n", held.daemon.c_str(),
                  held.duplicate ? "true" : "false", JsonOf(held.map).c_str());
    } else {
      std::printf("%-32s %-28s %-40s %s%s\n", held.map.name().c_str(), held.daemon.c_str(), Shape(held.map).c_str(),
                  FormatTimestamp(held.map.create_time()).c_str(), held.duplicate ? " DUPLICATE" : "");
    }
  }
  if (!fleet.duplicates.empty()) {
    std::fprintf(stderr, "fremenctl maps list: %zu maps are held by more than one daemon (a move in progress?)\n",
                 fleet.duplicates.size());
  }
  if (!fleet.Unreachable().empty()) throw CLI::RuntimeError(kExitFailure);
}

void RegisterList(CLI::App& maps) {
  auto json = std::make_shared<bool>(false);
  CLI::App* list = maps.add_subcommand("list", "List the maps, in name order");
  list->add_flag("--json", *json, "one JSON object per map");
  list->footer("With several daemons (--address A,B,C) every daemon is asked: the maps of all of them, with a DAEMON "
               "column;\nexit 1 when one does not answer (the others are listed).");
  list->callback([json] {
    if (NamesAFleet()) return ListFleet(*json);
    Client client = ConnectOrExit("maps list");
    auto all = client.ListAllMaps(GlobalCall());
    if (!all.ok()) FailCall("maps list", "listing maps", all.status());
    if (*json) {
      for (const v1::Map& map : *all) PrintJson(map);
      return;
    }
    if (all->empty()) {
      std::printf("no maps yet: create one with `fremenctl maps create NAME --resolution R --size X Y`\n");
      return;
    }
    std::printf("%-32s %-40s %s\n", "NAME", "SHAPE", "CREATED");
    for (const v1::Map& map : *all) {
      std::printf("%-32s %-40s %s\n", map.name().c_str(), Shape(map).c_str(),
                  FormatTimestamp(map.create_time()).c_str());
    }
  });
}

void RegisterGet(CLI::App& maps) {
  struct Args {
    std::string name;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* get = maps.add_subcommand("get", "Show a map's settings");
  get->add_option("name", a->name, "the map")->required();
  get->add_flag("--json", a->json, "as JSON");
  get->callback([a] {
    Client client = ConnectOrExit("maps get");
    auto map = client.GetMap(a->name, GlobalCall());
    if (!map.ok()) FailCall("maps get", a->name, map.status(), a->name);
    a->json ? PrintJson(*map) : PrintMap(*map);
  });
}

void RegisterDelete(CLI::App& maps) {
  struct Args {
    std::string name;
    bool yes = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* del = maps.add_subcommand("delete", "Delete a map and all its data");
  del->add_option("name", a->name, "the map")->required();
  del->add_flag("--yes", a->yes, "yes, delete it: its data cannot be recovered (short of a backup)");
  del->callback([a] {
    if (!a->yes) {
      FailUsage("maps delete", absl::StrCat("deleting map \"", a->name,
                                            "\" removes all its data; add --yes to confirm (`fremenctl backup --map ",
                                            a->name, " --to DIR` keeps a copy)"));
    }
    Client client = ConnectOrExit("maps delete");
    if (absl::Status deleted = client.DeleteMap(a->name, GlobalCall()); !deleted.ok()) {
      FailCall("maps delete", a->name, deleted, a->name);
    }
    std::printf("deleted map %s\n", a->name.c_str());
  });
}

}  // namespace

void RegisterMapsCommand(CLI::App& app) {
  CLI::App* maps = app.add_subcommand("maps", "Create, list, show and delete maps");
  maps->require_subcommand(1);
  RegisterCreate(*maps);
  RegisterList(*maps);
  RegisterGet(*maps);
  RegisterDelete(*maps);
}

}  // namespace fremen::client
