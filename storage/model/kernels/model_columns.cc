#include "storage/model/kernels/model_columns.h"

#include <algorithm>
#include <cassert>

namespace fremen::model {

ModelColumns::ModelColumns(int max_order) : k_(max_order), a_(max_order), b_(max_order) {}

namespace {
// `column` holds n models and kReadablePast zeros after them (also after a shrink).
template <typename T>
void ResizeColumn(std::vector<T>& column, size_t n) {
  column.resize(n + ModelColumns::kReadablePast);
  std::fill(column.begin() + static_cast<std::ptrdiff_t>(n), column.end(), T{0});
}
}  // namespace

void ModelColumns::Resize(size_t n) {
  order_.resize(n);
  ResizeColumn(alpha0_, n);
  for (int j = 0; j < max_order(); ++j) {
    ResizeColumn(k_[j], n);
    ResizeColumn(a_[j], n);
    ResizeColumn(b_[j], n);
  }
}

void ModelColumns::SetZero(size_t i, const CompactModels& models, size_t r) {
  assert(models.max_order() == max_order());
  const CompactModelHeader& h = models.header(r);
  alpha0_[i] = h.alpha0;
  order_[i] = h.order;
  // The components past the own order stay zero (the record's past count are zero too).
  const int own = std::min<int>(h.order, max_order());
  for (int j = 0; j < own; ++j) {
    k_[j][i] = models.k(r)[j];
    a_[j][i] = models.a(r)[j];
    b_[j][i] = models.b(r)[j];
  }
}

size_t ModelColumns::memory_bytes() const {
  size_t bytes = sizeof(*this) + alpha0_.capacity() * sizeof(float) + order_.capacity();
  for (int j = 0; j < max_order(); ++j) {
    bytes += k_[j].capacity() * sizeof(uint16_t) + (a_[j].capacity() + b_[j].capacity()) * sizeof(float);
  }
  return bytes;
}

}  // namespace fremen::model
