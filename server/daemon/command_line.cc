#include "server/daemon/command_line.h"

#include <map>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"

namespace fremen::server {

namespace {

std::string FlagOf(absl::string_view key) { return absl::StrCat("--", absl::StrReplaceAll(key, {{"_", "-"}})); }

// The arguments after the program's name, in the reversed order CLI11's vector parse expects, with
// `--flag=` split into `--flag` and an empty value: CLI11 would otherwise take the next argument
// as the value, while `--update-schedule=` means "an empty schedule" (never).
std::vector<std::string> ArgumentsForCli11(int argc, const char* const* argv) {
  std::vector<std::string> args;
  for (int i = argc - 1; i >= 1; --i) {
    const absl::string_view arg = argv[i];
    if (arg.size() > 3 && arg.substr(0, 2) == "--" && arg.back() == '=') {
      args.emplace_back();
      args.emplace_back(arg.substr(0, arg.size() - 1));
    } else {
      args.emplace_back(arg);
    }
  }
  return args;
}

}  // namespace

CommandLine ParseCommandLine(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app("fremend: the fremen FreMEn map database daemon (gRPC)", "fremend");
  app.footer(
      "Settings: embedded defaults, then --config FILE, then these flags (see deploy/fremend.conf.example).\n"
      "Exit codes: 0 stopped by SIGTERM/SIGINT, 1 failure, 2 bad command line or configuration;\n"
      "with --verify: 0 clean, 1 a problem found.");
  std::string config_file;
  bool check_config = false;
  app.add_option("--config", config_file, "config file of `key = value` lines")->type_name("FILE");
  app.add_flag("--check-config", check_config, "check the configuration (and the files it names), then exit");
  bool verify = false;
  app.add_flag("--verify", verify,
               "verify every map of data_dir offline (every record, log and checkpoint), print a report, then exit: "
               "0 clean, 1 problems found; refused while a daemon runs on data_dir");
  app.set_version_flag("--version", FREMEN_VERSION);

  // Flags keep their text until the file has been read: they override it.
  const ServerConfig defaults;
  std::map<std::string, std::string> flag_values;
  std::map<std::string, CLI::Option*> flag_options;
  for (const ConfigField& field : ConfigFields()) {
    const std::string key(field.key);
    CLI::Option* option = app.add_option(FlagOf(key), flag_values[key], std::string(field.help));
    option->type_name(std::string(field.value_name));
    if (const std::string value = field.get(defaults); !value.empty()) option->default_str(value);
    flag_options[key] = option;
  }

  try {
    std::vector<std::string> args = ArgumentsForCli11(argc, argv);
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e, out, err);
    return {std::nullopt, code == 0 ? kExitOk : kExitBadConfig};
  }

  ServerConfig config;
  absl::Status status;
  if (!config_file.empty()) status = ApplyConfigFile(config_file, config);
  for (const ConfigField& field : ConfigFields()) {
    if (!status.ok()) break;
    const std::string key(field.key);
    if (flag_options[key]->count() == 0) continue;
    status = SetConfigValue(key, flag_values[key], FlagOf(key), config);
  }
  if (status.ok()) status = FinishConfig(config);
  if (!status.ok()) {
    err << status.message() << "\n";
    return {std::nullopt, kExitBadConfig};
  }
  if (check_config) {
    out << "config OK\n";
    return {std::nullopt, kExitOk};
  }
  return {.config = std::move(config), .exit_code = kExitOk, .verify = verify};
}

}  // namespace fremen::server
