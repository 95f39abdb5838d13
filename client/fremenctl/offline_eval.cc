// Offline evaluation: file reading and the per-order score table (see offline_eval.h).
#include "client/fremenctl/offline_eval.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <algorithm>
#include <fstream>
#include <span>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "storage/model/phasor.h"
#include "storage/model/state_model.h"

namespace fremen::client {

namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// The next blank-separated token of `rest` (empty at the end), consuming it.
std::string_view NextToken(std::string_view& rest) {
  size_t begin = 0;
  while (begin < rest.size() && IsBlank(rest[begin])) ++begin;
  size_t end = begin;
  while (end < rest.size() && !IsBlank(rest[end])) ++end;
  std::string_view token = rest.substr(begin, end - begin);
  rest.remove_prefix(end);
  return token;
}

// A whole token as a double ("nan" and "inf" parse, so that validation can name them).
bool ParseDouble(std::string_view token, double& value) {
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

// Parses one non-blank line into `o`; the error does not yet name the place. (Views enter messages
// as std::string: Debian's abseil has its own string_view type, which StrCat does not take from std.)
absl::Status ParseLine(std::string_view line, model::Observation& o) {
  std::string_view rest = line;
  const std::string_view time_token = NextToken(rest);
  const std::string_view state_token = NextToken(rest);
  if (state_token.empty() || !NextToken(rest).empty()) {
    return absl::InvalidArgumentError(absl::StrCat("expected `time state`, got \"", std::string(line), "\""));
  }
  double t, s;
  if (!ParseDouble(time_token, t)) {
    return absl::InvalidArgumentError(absl::StrCat("time is not a number: \"", std::string(time_token), "\""));
  }
  if (!ParseDouble(state_token, s)) {
    return absl::InvalidArgumentError(absl::StrCat("state is not a number: \"", std::string(state_token), "\""));
  }
  // Checked in double: a value just above 1 would otherwise round into range as a float.
  if (!(s >= 0.0 && s <= 1.0)) {
    return absl::InvalidArgumentError(absl::StrCat("state must be in [0, 1], got ", std::string(state_token)));
  }
  o = {t, static_cast<float>(s)};
  // The daemon's own check of an observation, so that offline and online accept the same data.
  return model::ValidateObservation(o, "observation");
}

}  // namespace

absl::StatusOr<std::vector<model::Observation>> ReadObservations(std::istream& in, const std::string& name) {
  std::vector<model::Observation> observations;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::string_view rest = line;
    const std::string_view first = NextToken(rest);
    if (first.empty() || first.front() == '#') continue;
    model::Observation o;
    if (absl::Status status = ParseLine(line, o); !status.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(name, ":", number, ": ", status.message()));
    }
    observations.push_back(o);
  }
  if (in.bad()) return absl::DataLossError(absl::StrCat(name, ": read error"));
  if (observations.empty()) return absl::InvalidArgumentError(absl::StrCat(name, ": no observations"));
  return observations;
}

absl::StatusOr<std::vector<model::Observation>> ReadObservations(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open: ", std::strerror(errno)));
  return ReadObservations(in, path);
}

namespace {

// The scores of `order` of a published `state` on `test`.
OrderScore ScoreOrder(const model::StateModel& state, const model::ModelSettings& settings, int order,
                      const std::vector<model::Observation>& test, bool with_persistence) {
  OrderScore score{order};
  for (const model::Observation& o : test) {
    const double p = state.Predict(model::PhasorTable(settings.periods, o.t), with_persistence, order);
    score.err += std::fabs((p > 0.5 ? 1.0 : 0.0) - o.s);
    score.mse += (p - o.s) * (p - o.s);
  }
  score.err /= test.size();
  score.mse /= test.size();
  return score;
}

}  // namespace

OrderScore EvaluateReplay(const model::ModelSettings& settings, std::vector<model::Observation> train,
                          const std::vector<model::Observation>& test) {
  std::stable_sort(train.begin(), train.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  model::StateModel state(settings);
  const auto day_of = [](double t) { return std::floor(t / 86400.0); };
  for (size_t first = 0; first < train.size();) {
    size_t end = first;
    while (end < train.size() && day_of(train[end].t) == day_of(train[first].t)) ++end;
    state.AddBatch(std::span(train).subspan(first, end - first));
    state.Update();
    first = end;
  }
  return ScoreOrder(state, settings, state.published().order(), test, false);
}

std::vector<OrderScore> EvaluateOffline(const model::ModelSettings& settings,
                                        const std::vector<model::Observation>& train,
                                        const std::vector<model::Observation>& test, bool with_persistence) {
  model::StateModel state(settings);
  state.AddBatch(train);
  // P holds the same L strongest components whatever its selected order, so one publication at L
  // serves every order.
  state.Publish(settings.max_order);

  std::vector<OrderScore> scores;
  for (int order = 0; order <= settings.max_order; ++order) {
    scores.push_back(ScoreOrder(state, settings, order, test, with_persistence));
  }
  return scores;
}

}  // namespace fremen::client
