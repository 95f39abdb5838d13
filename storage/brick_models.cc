#include "storage/brick_models.h"

#include <algorithm>

namespace fremen::storage {

BrickModels::BrickModels(std::span<const BrickImage> images, const model::CompactModels& models, uint64_t generation)
    : generation_(generation), models_(models.max_order()) {
  size_t published = 0, total = 0;
  for (const BrickImage& image : images) {
    for (const BrickImage::DynamicCell& cell : image.dynamic()) published += models.published(cell.handle);
    total += image.dynamic().size();
  }
  models_.Resize(published);
  cells_.reserve(published);
  others_.reserve(total - published);
  bricks_.resize(images.size());
  for (size_t b = 0; b < images.size(); ++b) {
    Brick& brick = bricks_[b];
    brick.first = static_cast<uint32_t>(cells_.size());
    brick.others_first = static_cast<uint32_t>(others_.size());
    for (const BrickImage::DynamicCell& cell : images[b].dynamic()) {
      if (models.published(cell.handle)) {
        models_.SetZero(cells_.size(), models, cell.handle);
        cells_.push_back(static_cast<uint16_t>(cell.cell));
        brick.terms = std::max<int>(brick.terms, std::min<int>(models.header(cell.handle).order, models.max_order()));
      } else {
        others_.push_back(cell);
      }
    }
    brick.count = static_cast<uint32_t>(cells_.size()) - brick.first;
    brick.others_count = static_cast<uint32_t>(others_.size()) - brick.others_first;
    brick.covered = static_cast<uint32_t>(images[b].dynamic().size());
  }
}

size_t BrickModels::memory_bytes() const {
  return sizeof(*this) + bricks_.capacity() * sizeof(Brick) + models_.memory_bytes() +
         cells_.capacity() * sizeof(uint16_t) + others_.capacity() * sizeof(BrickImage::DynamicCell);
}

}  // namespace fremen::storage
