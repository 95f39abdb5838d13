#include "client/fremenctl/check_command.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

// A check reads the whole map: the global --timeout (meant for queries) is raised to at least this.
constexpr double kMinCheckSeconds = 600;

void PrintReport(const v1::CheckMapResponse& r) {
  for (const v1::CheckProblem& p : r.problems()) {
    std::printf("map %s: %s\n", r.map().c_str(), FormatCheckProblem(p).c_str());
  }
  for (const std::string& note : r.notes()) std::printf("map %s: note: %s\n", r.map().c_str(), note.c_str());
  uint64_t records = 0, bytes = 0, oldest = UINT64_MAX;
  for (const v1::ShardCheck& s : r.shards()) {
    records += s.records();
    bytes += s.file_bytes();
    oldest = std::min<uint64_t>(oldest, s.checkpoint_lsn());
  }
  std::printf(
      "map %s: %d shards, %llu records (%s), checkpoints from LSN %llu; log %llu segments, %llu records, "
      "LSN %llu..%llu; checked in %.2f s: %s\n",
      r.map().c_str(), r.shards_size(), static_cast<unsigned long long>(records), FormatBytes(bytes).c_str(),
      static_cast<unsigned long long>(oldest == UINT64_MAX ? 0 : oldest),
      static_cast<unsigned long long>(r.log().segments()), static_cast<unsigned long long>(r.log().records()),
      static_cast<unsigned long long>(r.log().first_lsn()), static_cast<unsigned long long>(r.log().last_lsn()),
      r.duration_seconds(), r.clean() ? "clean" : absl::StrCat(r.problems_size(), " problems found").c_str());
}

}  // namespace

void RegisterCheckCommand(CLI::App& app) {
  struct Args {
    std::string map;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* check = app.add_subcommand(
      "check", "Verify a map's files while it serves (every record, the log, the checkpoints), like fsck");
  check->add_option("map,--map", a->map, "the map")->required();
  check->add_flag("--json", a->json, "the report as JSON");
  check->footer(
      "Exit codes: 0 the map verified clean, 1 a problem was found (or the check failed), 2 bad usage.\n"
      "Offline, with the daemon stopped: fremend --config FILE --verify checks every map of its data_dir.");
  check->callback([a] {
    Client client = ConnectOrExit("check");
    CallOptions call = GlobalCall();
    call.timeout = std::max(*call.timeout, absl::Seconds(kMinCheckSeconds));
    auto report = client.CheckMap(a->map, call);
    if (!report.ok()) FailCall("check", absl::StrCat("map ", a->map), report.status(), a->map);
    if (a->json) {
      PrintJson(*report);
    } else {
      PrintReport(*report);
    }
    if (!report->clean()) throw CLI::RuntimeError(kExitFailure);
  });
}

}  // namespace fremen::client
