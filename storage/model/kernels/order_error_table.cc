#include "storage/model/kernels/order_error_table.h"

#include <algorithm>
#include <vector>

namespace fremen::model {

int OrderErrorTable::BestOrder(size_t i, const OrderRule& rule) const {
  const double* r = rec(i);
  return SelectOrder(r + kErrors, r[kWeight], max_order_, rule);
}

void OrderErrorTable::Reset(size_t i) {
  // As OrderErrors::Reset: the reference time stays.
  double* r = rec(i);
  std::fill(r + kWeight, r + kErrors + max_order_ + 1, 0.0);
}

OrderErrors OrderErrorTable::Get(size_t i) const {
  const double* r = rec(i);
  OrderErrors errors(max_order_);
  errors.Restore(r[kTRef], r[kWeight], std::vector<double>(r + kErrors, r + kErrors + max_order_ + 1));
  return errors;
}

void OrderErrorTable::Set(size_t i, const OrderErrors& errors) {
  double* r = rec(i);
  r[kTRef] = errors.reference_time();
  r[kWeight] = errors.weight();
  std::copy(errors.errors().begin(), errors.errors().end(), r + kErrors);
}

}  // namespace fremen::model
