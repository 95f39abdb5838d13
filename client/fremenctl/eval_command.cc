// `fremenctl eval`: options, then the offline evaluation of offline_eval.h, printed as a table.
#include "client/fremenctl/eval_command.h"

#include <cstdio>
#include <memory>
#include <string>

#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/offline_eval.h"
#include "storage/model/model_settings.h"
#include "storage/model/periods.h"

namespace fremen::client {

namespace {

struct EvalOptions {
  std::string train_path;
  std::string test_path;
  int periods = model::kDefaultPeriodCount;
  double longest = model::kWeekSeconds;
  bool floor_periods = false;
  int max_order = model::kDefaultMaxOrder;
  bool persistence = false;
  bool replay = false;
};

// The order rules --replay compares: the settings of maps made before the weighted rule (thresholded
// errors, 7-day half-life) with the paper's exact minimum and with the 0.001 margin, and the
// defaults of new maps.
struct ReplayRule {
  const char* name;
  model::ErrorCriterion criterion;
  double half_life;
  model::OrderRule rule;
};
constexpr ReplayRule kReplayRules[] = {
    {"paper", model::ErrorCriterion::kThreshold, 7 * 86400.0, model::OrderRule{model::OrderSelection::kPaper}},
    {"margin", model::ErrorCriterion::kThreshold, 7 * 86400.0, model::OrderRule{model::OrderSelection::kMargin}},
    {"default", model::kDefaultCriterion, model::kDefaultErrorHalfLife, model::OrderRule{}},
    {"weighted", model::ErrorCriterion::kSquared, 3 * 86400.0, model::OrderRule{model::OrderSelection::kWeighted}},
};

// Reports a failure on stderr and ends the program with `exit_code` (kExitFailure or kExitUsage).
[[noreturn]] void Fail(const absl::Status& status, int exit_code) {
  std::fprintf(stderr, "fremenctl eval: %s\n", std::string(status.message()).c_str());
  throw CLI::RuntimeError(exit_code);
}

void RunEval(const EvalOptions& options) {
  absl::StatusOr<model::PeriodSet> periods =
      model::PeriodSet::Harmonics(options.longest, options.periods, options.floor_periods);
  // Options that pass their own checks can still make an invalid Ω (a period floored to 0 s).
  if (!periods.ok()) Fail(periods.status(), kExitUsage);
  model::ModelSettings settings;
  settings.periods = *std::move(periods);
  settings.max_order = options.max_order;
  settings.persistence = options.persistence;

  absl::StatusOr<std::vector<model::Observation>> train = ReadObservations(options.train_path);
  if (!train.ok()) Fail(train.status(), kExitFailure);
  absl::StatusOr<std::vector<model::Observation>> test = ReadObservations(options.test_path);
  if (!test.ok()) Fail(test.status(), kExitFailure);

  for (const OrderScore& score : EvaluateOffline(settings, *train, *test, options.persistence)) {
    std::printf("%d\t%.4f\t%.4f\n", score.order, score.err, score.mse);
  }
  if (!options.replay) return;
  for (const ReplayRule& r : kReplayRules) {
    model::ModelSettings rule_settings = settings;
    rule_settings.criterion = r.criterion;
    rule_settings.error_half_life = r.half_life;
    rule_settings.order_rule = r.rule;
    const OrderScore score = EvaluateReplay(rule_settings, *train, *test);
    std::printf("%s\t%d\t%.4f\t%.4f\n", r.name, score.order, score.err, score.mse);
  }
}

}  // namespace

void RegisterEvalCommand(CLI::App& app) {
  // Owned by the callback, which outlives parsing.
  auto options = std::make_shared<EvalOptions>();
  CLI::App* eval = app.add_subcommand("eval", "Offline accuracy of the FreMEn model of one state on `time state` files");
  eval->add_option("--train", options->train_path, "Training data: one `time state` per line (seconds, [0, 1])")
      ->required()
      ->type_name("FILE");
  eval->add_option("--test", options->test_path, "Test data, same format")->required()->type_name("FILE");
  eval->add_option("--periods", options->periods, "Number of modelled periods K: T_k = longest / k, k = 1..K")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  eval->add_option("--longest", options->longest, "Longest modelled period in seconds (default: a week)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  eval->add_flag("--floor-periods", options->floor_periods,
                 "Round periods down to whole seconds, T_k = floor(longest / k), as the original FremenServer does");
  eval->add_option("--max-order", options->max_order, "Highest model order L evaluated (orders 0..L)")
      ->check(CLI::Range(0, model::kMaxMaxOrder))
      ->capture_default_str();
  eval->add_flag("--persistence", options->persistence,
                 "Blend the last training observation into the predictions (persistence model)");
  eval->add_flag("--replay", options->replay,
                 "Also feed --train day by day with nightly updates, as the daemon sees it, and print the test "
                 "scores of the order each rule selects (paper, margin, default, weighted)");
  eval->footer(
      "Trains one state on all of --train in one batch, then predicts every time of --test at each order\n"
      "0..L and prints one line per order: order<TAB>err<TAB>mse. err is the mean of |[p > 0.5] - s| (for 0/1\n"
      "states, the share of wrongly estimated samples), mse the mean of (p - s)^2.\n"
      "With --replay, four more lines rule<TAB>order<TAB>err<TAB>mse: the order selected after a day-by-day\n"
      "replay by the paper's rule (exact minimum of the thresholded errors, 7-day half-life), by the margin\n"
      "rule (the same, a higher order wins by > 0.001), by the default of new maps (the margin rule) and by\n"
      "the weighted rule on squared errors with a 3-day half-life (a map setting).\n"
      "Exit codes: 0 success, 1 unreadable or invalid data file (the message names file:line), 2 bad usage.\n"
      "\n"
      "Example, the setting of the original FremenServer's published figures:\n"
      "  fremenctl eval --train train.txt --test test.txt --periods 100 --floor-periods");
  eval->callback([options] { RunEval(*options); });
}

}  // namespace fremen::client
