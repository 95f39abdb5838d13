// `fremenctl model`: GetStateModel printed for people (or --json), and the p(t) plot drawn by
// formats/week_plot from a Predict over the plotted span.
#include "client/fremenctl/model_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/formats/png.h"
#include "client/formats/week_plot.h"
#include "client/fremenctl/cli_args.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/map_writer.h"
#include "client/fremenctl/offline_eval.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

constexpr char kCommand[] = "model";
constexpr double kDay = 86400;
// Samples of p(t) in a plot: one every ten minutes over a week.
constexpr int kPlotSamples = 1008;

struct ModelArgs {
  std::string map;
  std::string name;
  uint64_t id = 0;
  std::string cell;
  bool spectrum = false;
  bool json = false;
  std::string plot;
  std::string from;
  double days = 7;
  std::string observations;
};

void PrintComponents(const google::protobuf::RepeatedPtrField<v1::Component>& components) {
  std::printf("  %-14s %-10s %s\n", "period (h)", "amplitude", "phase (rad)");
  for (const v1::Component& c : components) {
    std::printf("  %-14.4f %-10.4f %+.4f\n", c.period_seconds() / 3600.0, c.amplitude(), c.phase());
  }
}

void PrintModel(const v1::StateModel& m) {
  if (m.has_cell()) std::printf("cell: %u %u %u\n", m.cell().x(), m.cell().y(), m.cell().z());
  std::printf("id: %llu\n", static_cast<unsigned long long>(m.id()));
  if (!m.name().empty()) std::printf("name: %s\n", m.name().c_str());
  if (!m.group().empty()) std::printf("group: %s\n", m.group().c_str());
  std::printf("observations: %llu from t = %.3f to %.3f\n", static_cast<unsigned long long>(m.observations()),
              m.first_time(), m.last_time());
  std::printf("mean (gamma0): %.4f\n", m.mean());
  if (m.never_changed()) {
    std::printf("never changed: p(t) is the mean at every time (no spectrum, no P)\n");
  } else {
    std::printf("published model P: alpha0 = %.4f, order %u\n", m.published_mean(), m.selected_order());
    if (m.published_size() > 0) PrintComponents(m.published());
  }
  if (m.order_errors_size() > 0) {
    std::printf("prediction error by order (decayed):\n  %-6s %-10s %s\n", "order", "error", "weight");
    for (const v1::OrderError& e : m.order_errors()) {
      std::printf("  %-6u %-10.4f %.1f%s\n", e.order(), e.error(), e.weight(),
                  e.order() == m.selected_order() && !m.never_changed() ? "  <- selected" : "");
    }
  }
  const v1::Persistence& p = m.persistence();
  std::printf("persistence: last s = %.2f at t = %.3f, tau = %.1f s\n", p.last_value(), p.last_time(), p.tau_seconds());
  if (m.has_lossless()) {
    const v1::LosslessModel& l = m.lossless();
    std::printf(
        "lossless: %llu slots of %g s from %.3f, %d outlier intervals, estimation error %.4f, prediction "
        "error %.4f\n",
        static_cast<unsigned long long>(l.slot_count()), l.sampling_seconds(), l.origin(), l.outliers_size(),
        l.estimation_error(), l.prediction_error());
  }
  if (m.spectrum_size() > 0) {
    std::printf("spectrum (%d components, amplitude 2|gamma_k|):\n", m.spectrum_size());
    PrintComponents(m.spectrum());
  }
}

// Draws p(t) from `from` over args.days, with the observations of --observations.
void Plot(const Client& client, const ModelArgs& args, const StateSet& states, const v1::StateModel& model,
          const std::string& label) {
  const bool png = absl::EndsWith(args.plot, ".png");
  if (!png && !absl::EndsWith(args.plot, ".svg")) FailUsage(kCommand, "--plot FILE must end in .svg or .png");
  formats::TimeSeriesPlot plot;
  if (args.from.empty()) {
    // The span ends a day after the last observation: reconstruction, then a day of prediction
    // (as the paper's Fig. 1).
    plot.start = model.last_time() - (args.days - 1) * kDay;
  } else {
    absl::StatusOr<double> from = ParseTimeArg(args.from);
    if (!from.ok()) FailUsage(kCommand, absl::StrCat("--from: ", from.status().message()));
    plot.start = *from;
  }
  plot.end = plot.start + args.days * kDay;
  plot.last_observation = model.last_time();
  plot.title = absl::StrCat(args.map, " / ", label, ": p(t) (green) and observations (red)");
  std::vector<double> times(kPlotSamples + 1);
  for (int i = 0; i <= kPlotSamples; ++i) times[i] = plot.start + (plot.end - plot.start) * i / kPlotSamples;
  absl::StatusOr<Predictions> predictions = client.Predict(args.map, states, times, {}, GlobalCall());
  if (!predictions.ok()) FailCall(kCommand, "cannot predict", predictions.status(), args.map);
  for (size_t i = 0; i < times.size(); ++i) plot.probability.push_back({times[i], predictions->probability(i, 0)});
  if (!args.observations.empty()) {
    absl::StatusOr<std::vector<model::Observation>> observations = ReadObservations(args.observations);
    if (!observations.ok()) FailInput(kCommand, observations.status());
    for (const model::Observation& o : *observations) plot.observations.push_back({o.t, o.s});
  }
  absl::Status written;
  if (png) {
    written = formats::WritePng(args.plot, formats::RenderRaster(plot));
  } else {
    FILE* out = std::fopen(args.plot.c_str(), "w");
    const std::string svg = formats::RenderSvg(plot);
    if (out == nullptr || std::fwrite(svg.data(), 1, svg.size(), out) != svg.size()) {
      written = absl::PermissionDeniedError(absl::StrCat(args.plot, ": cannot write"));
    }
    if (out != nullptr && std::fclose(out) != 0 && written.ok()) {
      written = absl::DataLossError(absl::StrCat(args.plot, ": write error"));
    }
  }
  if (!written.ok()) FailInput(kCommand, written);
  std::printf("plot: %s (p(t) from t = %.0f over %g days)\n", args.plot.c_str(), plot.start, args.days);
}

void RunModel(const ModelArgs& args) {
  const int refs = !args.name.empty() + (args.id != 0) + !args.cell.empty();
  if (refs != 1) FailUsage(kCommand, "name the state with exactly one of --name NAME, --id ID or --cell X,Y[,Z]");
  v1::StateRef ref;
  std::optional<StateSet> states;
  std::string label;
  if (!args.name.empty()) {
    ref = State::Named(args.name);
    states = StateSet::Names({args.name});
    label = args.name;
  } else if (args.id != 0) {
    ref = State::WithId(args.id);
    states = StateSet::Ids({args.id});
    label = absl::StrCat("id ", args.id);
  } else {
    absl::StatusOr<Cell> cell = ParseCellArg(args.cell);
    if (!cell.ok()) FailUsage(kCommand, absl::StrCat("--cell: ", cell.status().message()));
    ref = State::AtCell(*cell);
    states = StateSet::Cells({*cell});
    label = absl::StrCat("cell ", cell->x, ",", cell->y, ",", cell->z);
  }

  const Client client = ConnectOrExit(kCommand);
  absl::StatusOr<std::optional<v1::StateModel>> model =
      client.GetStateModel(args.map, ref, args.spectrum, GlobalCall());
  if (!model.ok()) FailCall(kCommand, "cannot read the state's model", model.status(), args.map);
  if (!model->has_value()) {
    FailInput(kCommand, absl::NotFoundError(
                            absl::StrCat(label, " has never been observed in map ", args.map, " (it predicts 0.5)")));
  }
  if (args.json) {
    PrintJson(**model);
  } else {
    PrintModel(**model);
  }
  if (!args.plot.empty()) Plot(client, args, *states, **model, label);
}

}  // namespace

void RegisterModelCommand(CLI::App& app) {
  auto args = std::make_shared<ModelArgs>();
  CLI::App* cmd = app.add_subcommand("model", "Print one state's model; --plot draws a week of p(t)");
  cmd->add_option("--map", args->map, "The map")->required()->type_name("MAP");
  cmd->add_option("--name", args->name, "A generic state by name")->type_name("NAME");
  cmd->add_option("--id", args->id, "A generic state by id")->type_name("ID")->check(CLI::PositiveNumber);
  cmd->add_option("--cell", args->cell, "A grid cell by indices")->type_name("X,Y[,Z]");
  cmd->add_flag("--spectrum", args->spectrum, "Also print the whole spectrum (every modelled period)");
  cmd->add_flag("--json", args->json, "Print the model as JSON (the API's StateModel message)");
  cmd->add_option("--plot", args->plot, "Draw p(t) and the observations into FILE.svg or FILE.png")->type_name("FILE");
  cmd->add_option("--from", args->from, "Start of the plot (default: --days - 1 days before the last observation)")
      ->type_name("TIME");
  cmd->add_option("--days", args->days, "Length of the plot in days")
      ->check(CLI::Range(0.01, 366.0))
      ->capture_default_str();
  cmd->add_option("--observations", args->observations, "A `time state` file whose observations the plot shows")
      ->type_name("FILE");
  cmd->footer(
      "Prints what fremend knows of the state: observations, the mean, the published model P (its\n"
      "components: period, amplitude alpha, phase phi of alpha cos(2 pi t / period + phi)), the decayed\n"
      "prediction error of every order (the update job selects the lowest), and persistence.\n"
      "--plot draws p(t) (green) every 1/1008 of the span, the observations of --observations (red;\n"
      "fremend keeps models, not raw data) and the last observation's time (blue), like Figs. 1-2 of the\n"
      "FreMEn paper: left of the line the model reconstructs, right of it it predicts.\n"
      "Exit codes: 0 success, 1 unknown map or state, daemon error or bad file, 2 bad usage.\n"
      "\n"
      "Example: fremenctl model --map demo-states --name door --plot door.svg");
  cmd->callback([args] { RunModel(*args); });
}

}  // namespace fremen::client
