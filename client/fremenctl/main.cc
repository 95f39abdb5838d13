// fremenctl: the command line of fremen. main() only builds the CLI11 application from the
// subcommands and maps its outcome to the exit code: 0 success (or help), 1 the command failed
// (e.g. bad input file), 2 bad usage.
#include "CLI/CLI.hpp"
#include "client/fremenctl/admin_commands.h"
#include "client/fremenctl/bench_command.h"
#include "client/fremenctl/check_command.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/demo_command.h"
#include "client/fremenctl/eval_command.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/fleet_command.h"
#include "client/fremenctl/ingest_command.h"
#include "client/fremenctl/maps_command.h"
#include "client/fremenctl/model_command.h"
#include "client/fremenctl/operations_command.h"
#include "client/fremenctl/query_commands.h"
#include "client/fremenctl/region_command.h"
#include "client/fremenctl/salvage_command.h"
#include "client/fremenctl/transfer_commands.h"
#include "client/fremenctl/update_command.h"

int main(int argc, char** argv) {
  CLI::App app("fremenctl: the command line of the fremen FreMEn map database", "fremenctl");
  app.require_subcommand(1);
  app.footer("Run `fremenctl SUBCOMMAND --help` for a subcommand's options.\n"
             "Exit codes: 0 success, 1 the command failed, 2 bad usage.");
  fremen::client::AddGlobalOptions(app);
  fremen::client::RegisterEvalCommand(app);
  fremen::client::RegisterMapsCommand(app);
  fremen::client::RegisterPredictCommand(app);
  fremen::client::RegisterTopCommand(app);
  fremen::client::RegisterStatesCommand(app);
  fremen::client::RegisterAnomaliesCommand(app);
  fremen::client::RegisterStatsCommand(app);
  fremen::client::RegisterUpdateCommand(app);
  fremen::client::RegisterOperationsCommand(app);
  fremen::client::RegisterBackupCommand(app);
  fremen::client::RegisterRestoreCommand(app);
  fremen::client::RegisterExportCommand(app);
  fremen::client::RegisterImportCommand(app);
  fremen::client::RegisterStatusCommand(app);
  fremen::client::RegisterCheckCommand(app);
  fremen::client::RegisterSalvageCommand(app);
  fremen::client::RegisterIngestCommand(app);
  fremen::client::RegisterRegionCommand(app);
  fremen::client::RegisterModelCommand(app);
  fremen::client::RegisterDemoCommand(app);
  fremen::client::RegisterBenchCommand(app);
  fremen::client::RegisterFleetCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    // A command failed and has said why.
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    // Prints help (exit 0) or the usage error; CLI11's own codes (100+) are mapped to one.
    const int code = app.exit(e);
    return code == 0 ? fremen::client::kExitOk : fremen::client::kExitUsage;
  }
  return fremen::client::kExitOk;
}
