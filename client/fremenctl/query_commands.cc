// The query subcommands: each parses its states and times (cli_args.h), makes one call through the
// client library and prints a table (or JSON for stats).
#include "client/fremenctl/query_commands.h"

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/time/time.h"
#include "client/fremenctl/cli_args.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

// The options naming states, shared by predict and anomalies.
void AddStateOptions(CLI::App& command, StateArgs& states) {
  command.add_option("--cell", states.cells, "grid cell X,Y[,Z] (repeat for more)")->group("States");
  command.add_option("--point", states.points, "metric point X,Y[,Z] in metres (repeat for more)")->group("States");
  command.add_option("--id", states.ids, "generic state id (repeat for more)")->group("States");
  command.add_option("--name", states.names, "generic state name (repeat for more)")->group("States");
}

void AddModelOptions(CLI::App& command, ModelOptions& model) {
  command.add_flag("--persistence", model.persistence, "blend in the last observation (persistence model)");
  command.add_option("--order", model.order, "evaluate at this order instead of each state's selected one")
      ->check(CLI::NonNegativeNumber);
}

// How a state is shown: as given on the command line.
std::vector<std::string> StateLabels(const StateArgs& args) {
  if (!args.cells.empty()) return args.cells;
  if (!args.points.empty()) return args.points;
  if (!args.names.empty()) return args.names;
  std::vector<std::string> labels;
  for (uint64_t id : args.ids) labels.push_back(absl::StrCat(id));
  return labels;
}

std::string TimeLabel(double seconds) {
  return absl::FormatTime("%Y-%m-%dT%H:%M:%SZ", absl::FromUnixSeconds(static_cast<int64_t>(seconds)),
                          absl::UTCTimeZone());
}

template <typename T>
T OrUsage(absl::string_view command, absl::StatusOr<T> value) {
  if (!value.ok()) FailUsage(command, value.status().message());
  return *std::move(value);
}

}  // namespace

void RegisterPredictCommand(CLI::App& app) {
  struct Args {
    std::string map;
    StateArgs states;
    std::vector<std::string> times;
    ModelOptions model;
    std::optional<float> confidence;
  };
  auto a = std::make_shared<Args>();
  CLI::App* predict = app.add_subcommand("predict", "Probability that states are 1 (occupied, open) at times");
  predict->add_option("--map", a->map, "the map")->required();
  AddStateOptions(*predict, a->states);
  predict->add_option("--time", a->times, "when: now, seconds since 1970, or RFC 3339 (repeat for more)")->required();
  AddModelOptions(*predict, a->model);
  predict->add_option("--confidence", a->confidence, "also print the state p ≥ C as 0/1")->check(CLI::Range(0.0, 1.0));
  predict->footer("Example: fremenctl predict --map office --cell 12,40 --time 2026-11-23T08:00:00Z");
  predict->callback([a] {
    const StateSet states = OrUsage("predict", ParseStateArgs(a->states));
    const std::vector<double> times = OrUsage("predict", ParseTimeArgs(a->times));
    Client client = ConnectOrExit("predict");
    PredictOptions options{.model = a->model, .confidence = a->confidence, .states_only = false};
    auto p = client.Predict(a->map, states, times, options, GlobalCall());
    if (!p.ok()) FailCall("predict", absl::StrCat("map ", a->map), p.status(), a->map);
    const std::vector<std::string> labels = StateLabels(a->states);
    std::vector<bool> unobserved(labels.size());
    for (uint32_t j : p->unobserved) unobserved[j] = true;
    std::printf("%-20s  %-20s  %-6s%s\n", "TIME", "STATE", "P", a->confidence ? "  P>=C" : "");
    for (uint32_t i = 0; i < p->time_count; ++i) {
      for (uint32_t j = 0; j < p->state_count; ++j) {
        std::string line = absl::StrFormat("%-20s  %-20s  %.4f", TimeLabel(times[i]), labels[j], p->probability(i, j));
        if (a->confidence) absl::StrAppend(&line, "  ", p->states[i * p->state_count + j] ? 1 : 0);
        if (unobserved[j]) absl::StrAppend(&line, "  (never observed)");
        std::printf("%s\n", line.c_str());
      }
    }
  });
}

void RegisterTopCommand(CLI::App& app) {
  struct Args {
    std::string map, group, time = "now";
    uint32_t n = 10;
    ModelOptions model;
  };
  auto a = std::make_shared<Args>();
  CLI::App* top = app.add_subcommand("top", "The states of a group most likely to be 1 at a time (generic maps)");
  top->add_option("--map", a->map, "the map")->required();
  top->add_option("--group", a->group, "the group, as named at ingest")->required();
  top->add_option("--time", a->time, "when: now, seconds since 1970, or RFC 3339")->capture_default_str();
  top->add_option("-n", a->n, "how many")->check(CLI::Range(1, 10000))->capture_default_str();
  AddModelOptions(*top, a->model);
  top->callback([a] {
    const double time = OrUsage("top", ParseTimeArg(a->time));
    Client client = ConnectOrExit("top");
    auto states = client.TopStates(a->map, a->group, time, a->n, a->model, GlobalCall());
    if (!states.ok()) FailCall("top", absl::StrCat("group ", a->group, " of map ", a->map), states.status(), a->map);
    std::printf("%-4s  %-20s  %-24s  %s\n", "RANK", "ID", "NAME", "P");
    int rank = 0;
    for (const v1::ScoredState& s : *states) {
      std::printf("%-4d  %-20llu  %-24s  %.4f\n", ++rank, static_cast<unsigned long long>(s.id()),
                  s.name().empty() ? "-" : s.name().c_str(), s.probability());
    }
  });
}

void RegisterStatesCommand(CLI::App& app) {
  struct Args {
    std::string map, group;
  };
  auto a = std::make_shared<Args>();
  CLI::App* states = app.add_subcommand("states", "The named states of a generic map (or of one group), by name");
  states->add_option("--map", a->map, "the map")->required();
  states->add_option("--group", a->group, "only this group's states");
  states->callback([a] {
    Client client = ConnectOrExit("states");
    auto listed = client.ListAllStates(a->map, a->group, GlobalCall());
    if (!listed.ok()) FailCall("states", absl::StrCat("map ", a->map), listed.status(), a->map);
    std::printf("%-20s  %-24s  %s\n", "ID", "NAME", "GROUP");
    for (const v1::NamedState& s : *listed) {
      std::printf("%-20llu  %-24s  %s\n", static_cast<unsigned long long>(s.id()),
                  s.name().empty() ? "-" : s.name().c_str(), s.group().empty() ? "-" : s.group().c_str());
    }
  });
}

void RegisterAnomaliesCommand(CLI::App& app) {
  struct Args {
    std::string map;
    StateArgs states;
    std::vector<float> values;
    std::vector<std::string> times;
    float confidence = 0.9f;
    ModelOptions model;
  };
  auto a = std::make_shared<Args>();
  CLI::App* anomalies = app.add_subcommand("anomalies", "Which observations contradict the model at a confidence");
  anomalies->add_option("--map", a->map, "the map")->required();
  AddStateOptions(*anomalies, a->states);
  anomalies->add_option("--value", a->values, "the observed value of each state, in [0, 1], in the same order")
      ->required()
      ->check(CLI::Range(0.0, 1.0));
  anomalies->add_option("--time", a->times, "when each was observed (one time for all, or one per state)")->required();
  anomalies->add_option("--confidence", a->confidence, "in [0.5, 1]")
      ->check(CLI::Range(0.5, 1.0))
      ->capture_default_str();
  AddModelOptions(*anomalies, a->model);
  anomalies->footer("Exit code 0 whether or not anomalies were found; the last line counts them.");
  anomalies->callback([a] {
    const StateSet states = OrUsage("anomalies", ParseStateArgs(a->states));
    const std::vector<double> times = OrUsage("anomalies", ParseTimeArgs(a->times));
    if (a->values.size() != states.size()) {
      FailUsage("anomalies", absl::StrCat("give one --value per state: ", states.size(), " states but ",
                                          a->values.size(), " values"));
    }
    if (times.size() != 1 && times.size() != states.size()) {
      FailUsage("anomalies", absl::StrCat("give one --time for all states or one per state: ", states.size(),
                                          " states but ", times.size(), " times"));
    }
    Client client = ConnectOrExit("anomalies");
    auto result = client.CheckAnomalies(a->map, states, a->values, times, a->confidence, a->model, GlobalCall());
    if (!result.ok()) FailCall("anomalies", absl::StrCat("map ", a->map), result.status(), a->map);
    const std::vector<std::string> labels = StateLabels(a->states);
    std::printf("%-20s  %-5s  %-6s  %s\n", "STATE", "VALUE", "P", "ANOMALOUS");
    size_t count = 0;
    for (size_t i = 0; i < result->size(); ++i) {
      const Anomaly& x = (*result)[i];
      count += x.anomalous;
      std::printf("%-20s  %-5g  %.4f  %s\n", labels[i].c_str(), a->values[i], x.probability,
                  x.anomalous ? "yes" : "no");
    }
    std::printf("%zu of %zu observations anomalous at confidence %g\n", count, result->size(), a->confidence);
  });
}

void RegisterStatsCommand(CLI::App& app) {
  struct Args {
    std::string map;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* stats = app.add_subcommand("stats", "A map's statistics: states, observations, model orders, sizes");
  stats->add_option("--map", a->map, "the map")->required();
  stats->add_flag("--json", a->json, "as JSON");
  stats->callback([a] {
    Client client = ConnectOrExit("stats");
    auto s = client.GetMapStats(a->map, GlobalCall());
    if (!s.ok()) FailCall("stats", absl::StrCat("map ", a->map), s.status(), a->map);
    if (a->json) return PrintJson(*s);
    std::printf("map: %s\n", a->map.c_str());
    std::printf("states: %llu (%llu dynamic)\n", static_cast<unsigned long long>(s->states()),
                static_cast<unsigned long long>(s->dynamic_states()));
    std::printf("observations: %llu\n", static_cast<unsigned long long>(s->observations()));
    std::printf("orders: %s (dynamic states by selected order 0..L)\n",
                absl::StrJoin(s->order_histogram(), " ").c_str());
    std::printf("mean prediction error: %.4f\n", s->mean_prediction_error());
    std::printf("compression ratio: %.1f\n", s->compression_ratio());
    std::printf("disk: %s, memory: %s, log: %s\n", FormatBytes(s->disk_bytes()).c_str(),
                FormatBytes(s->memory_bytes()).c_str(), FormatBytes(s->log_bytes()).c_str());
    if (s->lossless_estimation_error() > 0 || s->lossless_prediction_error() > 0) {
      std::printf("lossless errors: estimation %.4f, prediction %.4f\n", s->lossless_estimation_error(),
                  s->lossless_prediction_error());
    }
  });
}

}  // namespace fremen::client
