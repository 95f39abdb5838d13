#include "storage/model/order_selection.h"

#include <algorithm>
#include <cmath>

namespace fremen::model {

namespace {
constexpr int kMaxRuleOrder = 64;  // kMaxMaxOrder, which model_settings.h (above this file) defines
}  // namespace

void OrderWeights(const double* errors, double weight, int max_order, double temperature, double* out) {
  const int n = max_order + 1;
  if (weight <= 0) {
    std::fill(out, out + n, 1.0 / n);
    return;
  }
  const double best = *std::min_element(errors, errors + n) / weight;
  double sum = 0;
  for (int l = 0; l < n; ++l) {
    out[l] = std::exp(-(errors[l] / weight - best) / temperature);  // ≤ 1, and 1 at the best
    sum += out[l];
  }
  for (int l = 0; l < n; ++l) out[l] /= sum;
}

int SelectOrder(const double* errors, double weight, int max_order, const OrderRule& rule) {
  if (weight <= 0) return 0;
  if (rule.selection == OrderSelection::kWeighted) {
    double w[kMaxRuleOrder + 1];
    OrderWeights(errors, weight, max_order, rule.temperature, w);
    double mean = 0;
    for (int l = 0; l <= max_order; ++l) mean += w[l] * l;
    return std::min(max_order, static_cast<int>(std::floor(mean + 0.5)));
  }
  const double margin = rule.selection == OrderSelection::kPaper ? 0.0 : rule.margin;
  int best = 0;
  for (int l = 1; l <= max_order; ++l) {
    if (errors[l] / weight < errors[best] / weight - margin) best = l;
  }
  return best;
}

}  // namespace fremen::model
