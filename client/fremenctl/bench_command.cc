// `fremenctl bench ingest|query [-- ARGS...]` replaces itself with fremen_ingest_load or
// fremen_query_load, installed beside fremenctl, passing the global --address and --token and then
// ARGS as they are. The generators stay programs of their own (they measure a client, and a
// benchmark wants nothing else in its process); this command only spares an operator their names
// and the connection flags. Their output and exit code are the command's.
#include "client/fremenctl/bench_command.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"

namespace fremen::client {

namespace {

struct BenchArgs {
  std::string kind;
  std::vector<std::string> passed;  // the generator's own arguments
};

// The directory of the running fremenctl (the generators are built and installed beside it).
std::filesystem::path OwnDirectory() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path(".") : self.parent_path();
}

[[noreturn]] void RunGenerator(const BenchArgs& args) {
  const std::string program = args.kind == "ingest" ? "fremen_ingest_load" : "fremen_query_load";
  const std::filesystem::path path = OwnDirectory() / program;
  if (access(path.c_str(), X_OK) != 0) {
    std::fprintf(stderr,
                 "fremenctl bench: %s is not beside fremenctl (%s); build it with "
                 "`cmake --build build --target %s`\n",
                 program.c_str(), path.c_str(), program.c_str());
    throw CLI::RuntimeError(kExitFailure);
  }
  // Both generators take --name=value; fremen_query_load takes no other form.
  std::vector<std::string> argv = {program, absl::StrCat("--address=", Globals().address)};
  if (!Globals().token.empty()) argv.push_back(absl::StrCat("--token=", Globals().token));
  argv.insert(argv.end(), args.passed.begin(), args.passed.end());
  std::vector<char*> raw;
  for (std::string& a : argv) raw.push_back(a.data());
  raw.push_back(nullptr);
  std::fflush(stdout);
  execv(path.c_str(), raw.data());
  std::fprintf(stderr, "fremenctl bench: cannot run %s: %s\n", path.c_str(), std::strerror(errno));
  throw CLI::RuntimeError(kExitFailure);
}

}  // namespace

void RegisterBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* bench = app.add_subcommand(
      "bench", "run a load generator against the daemon: ingest (gRPC ingest with durable acknowledgements) or "
               "query (region and single-state prediction); arguments after -- go to the generator, e.g. "
               "`fremenctl bench ingest -- --streams 4 --seconds 5` (`fremenctl bench ingest -- --help` lists them)");
  bench->add_option("kind", args->kind, "ingest or query")->required()->check(CLI::IsMember({"ingest", "query"}));
  bench->add_option("args", args->passed, "the generator's arguments, after --");
  bench->callback([args] { RunGenerator(*args); });
}

}  // namespace fremen::client
