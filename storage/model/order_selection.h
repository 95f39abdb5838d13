// The rule that turns a state's decayed per-order error rates into its published order
// (docs/model.md, "Order selection"); shared by OrderErrors (one state) and OrderErrorTable (the
// scan kernels' table) so that both pick the same order.
// Thread-safety: pure functions.
#pragma once

#include <cstdint>

namespace fremen::model {

enum class OrderSelection : uint8_t {
  // The lowest rate; a higher order must beat the best lower one by more than `margin` (fremen's
  // rule before the weighted one, and the original FremenServer's with margin 0.001).
  kMargin = 0,
  // The exact minimum, ties to the lower order: the paper's rule (kMargin with margin 0).
  kPaper = 1,
  // The mean order under weights w_l ∝ exp(−(r_l − r_min)/temperature), rounded half up. Orders
  // whose rates are within a few temperatures of the best all pull on the choice, which shrinks a
  // choice made on noisy rates towards the middle of the near-ties instead of its extreme.
  kWeighted = 2,
};

inline constexpr double kDefaultOrderMargin = 0.001;
inline constexpr double kDefaultOrderTemperature = 0.01;

struct OrderRule {
  OrderSelection selection = OrderSelection::kMargin;
  double margin = kDefaultOrderMargin;            // kMargin only. REQUIRES: finite, ≥ 0
  double temperature = kDefaultOrderTemperature;  // kWeighted only. REQUIRES: finite, > 0
  bool operator==(const OrderRule&) const = default;
};

// The order for decayed error sums errors[0..max_order] over a decayed count `weight`. With no
// evidence (weight 0) every rule answers 0: a state not yet scored has no reason for components.
int SelectOrder(const double* errors, double weight, int max_order, const OrderRule& rule);

// The weights of kWeighted into out[0..max_order] (they sum to 1); uniform when weight is 0.
void OrderWeights(const double* errors, double weight, int max_order, double temperature, double* out);

}  // namespace fremen::model
