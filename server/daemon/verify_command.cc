#include "server/daemon/verify_command.h"

#include <sys/stat.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/daemon/command_line.h"
#include "server/daemon/data_dir_lock.h"
#include "storage/verify.h"

namespace fremen::server {

namespace {

void PrintProblems(const std::vector<storage::VerifyProblem>& problems, const std::string& prefix, std::ostream& out) {
  for (const storage::VerifyProblem& p : problems) out << prefix << storage::FormatProblem(p) << "\n";
}

void PrintMap(const storage::VerifyReport& map, std::ostream& out) {
  uint64_t records = 0, bytes = 0;
  for (const storage::ShardVerifyReport& s : map.shards) {
    records += s.records;
    bytes += s.file_bytes;
  }
  out << absl::StrFormat("map %s (%s): %u shards, %u records, %u bytes; log %u segments, %u records, LSN %u..%u\n",
                         map.map, map.dir, map.shards.size(), records, bytes, map.log.segments, map.log.records,
                         map.log.first_lsn, map.log.last_lsn);
  for (const storage::ShardVerifyReport& s : map.shards) {
    out << absl::StrFormat("  shard-%u: %u records, checkpoint %s\n", s.shard, s.records,
                           s.checkpoint_lsn ? absl::StrCat("at LSN ", *s.checkpoint_lsn) : std::string("none"));
  }
  PrintProblems(map.problems, absl::StrCat("  map ", map.map, ": "), out);
  for (const std::string& note : map.notes) out << "  note: " << note << "\n";
  out << absl::StrFormat("map %s: %s\n", map.map,
                         map.clean() ? std::string("clean") : absl::StrCat(map.problems.size(), " problems"));
}

}  // namespace

int VerifyDataDirCommand(const ServerConfig& config, std::ostream& out, std::ostream& err) {
  struct stat st;
  if (stat((config.data_dir + "/catalog").c_str(), &st) != 0) {
    err << "fremend --verify: data_dir " << config.data_dir << " holds no catalog: nothing to verify\n";
    return kExitFailure;
  }
  auto lock = DataDirLock::Acquire(config.data_dir);
  if (!lock.ok()) {
    err << "fremend --verify: " << lock.status().message()
        << "; stop it first, or check a map it serves with `fremenctl check MAP`\n";
    return kExitFailure;
  }
  storage::VerifyOptions options;
  options.isolate = true;
  const storage::DataDirVerifyReport report = storage::VerifyDataDir(config.data_dir, options);
  PrintProblems(report.problems, absl::StrCat(config.data_dir, ": "), out);
  size_t damaged = 0, problems = report.problems.size();
  for (const storage::VerifyReport& map : report.maps) {
    PrintMap(map, out);
    damaged += !map.clean();
    problems += map.problems.size();
  }
  out << absl::StrFormat("summary: %u maps verified, %u with problems, %u problems in all%s\n", report.maps.size(),
                         damaged, problems, report.problems.empty() ? "" : " (some in the catalog or maps directory)");
  return report.clean() ? kExitOk : kExitFailure;
}

}  // namespace fremen::server
