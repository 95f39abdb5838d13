// Offline evaluation of the FreMEn model of one state (`fremenctl eval`): read `time state`
// files, train one model on all the training data, and score its predictions of the test data at
// every order 0..L.
//
// This is the client's one use of the model maths (docs/model.md, "Where the maths is used"): it
// reproduces the original FremenServer's experiment (all training data in one batch, then a
// prediction at every test time) so that figures can be compared with the published ones.
// No threads; functions are pure apart from reading the named file.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/model/model_settings.h"
#include "storage/model/observation.h"

namespace fremen::client {

// Reads one observation per line, `time state` separated by blanks (time in seconds, state in
// [0, 1]). Blank lines and lines starting with '#' are skipped. Errors name `path:line`: a file
// that cannot be opened, a malformed line, a non-finite or absurd time, a state outside [0, 1], and
// a file without any observation.
absl::StatusOr<std::vector<model::Observation>> ReadObservations(const std::string& path);
// The same from a stream; errors name `name` in place of the path.
absl::StatusOr<std::vector<model::Observation>> ReadObservations(std::istream& in, const std::string& name);

// The scores of one order on the test data.
struct OrderScore {
  int order = 0;
  // Mean of |[p > 0.5] − s|: the share of test samples whose thresholded prediction is wrong for
  // hard states; soft states (a probability s) count the probability mass it gets wrong.
  double err = 0;
  // Mean of (p − s)², p clamped to [0, 1].
  double mse = 0;
};

// Trains one model with `settings` on all of `train` in one batch, then scores its predictions of
// every `test` time at orders 0..settings.max_order (with the persistence model blended in when
// `with_persistence` and settings.persistence are set). REQUIRES: `test` is not empty.
std::vector<OrderScore> EvaluateOffline(const model::ModelSettings& settings,
                                        const std::vector<model::Observation>& train,
                                        const std::vector<model::Observation>& test, bool with_persistence);

// The test scores of the order a rule selects when the training data are fed as the daemon sees
// them: one batch per UTC day (day = floor(t / 86400)), each scored prequentially against the model
// published the night before, then an update (order choice by `settings.criterion`,
// `settings.error_half_life` and `settings.order_rule`, publication). The test data are predicted
// with the last published model at its selected order, without persistence.
// REQUIRES: `train` and `test` are not empty.
OrderScore EvaluateReplay(const model::ModelSettings& settings, std::vector<model::Observation> train,
                          const std::vector<model::Observation>& test);

}  // namespace fremen::client
