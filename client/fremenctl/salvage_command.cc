#include "client/fremenctl/salvage_command.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

// A salvage reads the whole damaged map and writes a new one: the global --timeout (meant for queries) is raised to at
// least this.
constexpr double kMinSalvageSeconds = 600;

unsigned long long U(uint64_t v) { return static_cast<unsigned long long>(v); }

void PrintReport(const std::string& from, const v1::SalvageMapResponse& r) {
  for (const v1::CheckProblem& p : r.lost()) {
    std::printf("map %s: lost: %s: %s%s\n", from.c_str(), p.file().c_str(),
                p.location().empty() ? "" : absl::StrCat(p.location(), ": ").c_str(), p.description().c_str());
  }
  if (r.losses() > static_cast<uint64_t>(r.lost_size())) {
    std::printf("map %s: and %llu more losses not listed\n", from.c_str(), U(r.losses() - r.lost_size()));
  }
  for (const v1::ShardSalvage& s : r.shards()) {
    std::vector<std::string> parts;
    for (const v1::DatabaseSalvage& d : s.databases()) {
      if (d.kept() == 0 && d.lost() == 0) continue;
      parts.push_back(
          absl::StrCat(d.name(), " ", d.kept(), " kept", d.lost() > 0 ? absl::StrCat(" ", d.lost(), " lost") : ""));
    }
    std::printf("map %s: shard-%u: %s\n", from.c_str(), s.shard(),
                parts.empty() ? "empty" : absl::StrJoin(parts, ", ").c_str());
  }
  std::printf(
      "map %s salvaged as %s: %llu records kept, %llu lost; log %llu records kept, %llu lost (%s); %llu losses; in "
      "%.2f s\n",
      from.c_str(), r.map().name().c_str(), U(r.records_kept()), U(r.records_lost()), U(r.log_records_kept()),
      U(r.log_records_lost()), FormatBytes(r.log_bytes_lost()).c_str(), U(r.losses()), r.duration_seconds());
}

}  // namespace

void RegisterSalvageCommand(CLI::App& app) {
  struct Args {
    std::string map;
    std::string to;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* salvage = app.add_subcommand(
      "salvage", "Copy everything of a damaged map that verifies into a new map, and report what was lost");
  salvage->add_option("map,--map", a->map, "the damaged map (one that failed to open: fremenctl status)")->required();
  salvage->add_option("--to", a->to, "the new map's name (default: MAP-salvaged)");
  salvage->add_flag("--json", a->json, "the report as JSON");
  salvage->footer(
      "Only for a map that failed to open; a healthy map is copied with backup and restore. The damaged map and its\n"
      "files are left as they are: once the new map is judged good, `fremenctl maps delete MAP --yes` removes them.\n"
      "Exit codes: 0 the new map serves (losses are in the report), 1 the salvage failed, 2 bad usage.");
  salvage->callback([a] {
    Client client = ConnectOrExit("salvage");
    CallOptions call = GlobalCall();
    call.timeout = std::max(*call.timeout, absl::Seconds(kMinSalvageSeconds));
    auto report = client.SalvageMap(a->map, a->to, call);
    if (!report.ok()) FailCall("salvage", absl::StrCat("map ", a->map), report.status(), a->map);
    if (a->json) {
      PrintJson(*report);
    } else {
      PrintReport(a->map, *report);
    }
  });
}

}  // namespace fremen::client
