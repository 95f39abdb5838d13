#include "storage/model/kernels/compact_models.h"

#include <cassert>
#include <cstring>

namespace fremen::model {

CompactModels::CompactModels(int max_order, size_t size)
    : max_order_(max_order),
      a_offset_(kKOffset + KBytes(max_order)),
      b_offset_(a_offset_ + max_order * sizeof(float)),
      buffer_(StrideFor(max_order)) {
  Resize(size);
}

void CompactModels::Resize(size_t n) {
  const size_t old = size();
  buffer_.Resize(n);
  // Zero bytes are already the empty components; only the header's alpha0 differs.
  for (size_t i = old; i < n; ++i) header(i) = CompactModelHeader{};
  published_bits_.resize((n + 63) / 64, 0);
  if (n % 64 != 0) published_bits_.back() &= (uint64_t{1} << (n % 64)) - 1;  // a later growth starts unpublished
}

void CompactModels::Clear(size_t i, float alpha0) {
  std::memset(buffer_.record(i), 0, stride());
  header(i).alpha0 = alpha0;
  std::atomic_ref(published_bits_[i / 64]).fetch_and(~(uint64_t{1} << (i % 64)), std::memory_order_relaxed);
}

void CompactModels::SetUnpublished(size_t i, float alpha0) { Clear(i, alpha0); }

void CompactModels::Set(size_t i, const PublishedModel& model) {
  assert(model.components().size() <= static_cast<size_t>(max_order_));
  Clear(i, model.alpha0());
  MarkPublished(i);
  CompactModelHeader& h = header(i);
  h.order = static_cast<uint8_t>(model.order());
  h.count = static_cast<uint16_t>(model.components().size());
  for (size_t j = 0; j < model.components().size(); ++j) {
    const Component& c = model.components()[j];
    k(i)[j] = c.k;
    a(i)[j] = c.a;
    b(i)[j] = c.b;
  }
}

std::vector<Component> CompactModels::Components(size_t i) const {
  std::vector<Component> components(header(i).count);
  for (size_t j = 0; j < components.size(); ++j) components[j] = {k(i)[j], a(i)[j], b(i)[j]};
  return components;
}

PublishedModel CompactModels::Get(size_t i) const {
  const CompactModelHeader& h = header(i);
  return h.published ? PublishedModel::Restore(h.alpha0, h.order, Components(i)) : PublishedModel::MeanOnly(h.alpha0);
}

bool CompactModels::Holds(size_t i, const PublishedModel& model) const { return published(i) && Get(i) == model; }

}  // namespace fremen::model
