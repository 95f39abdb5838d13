#include "storage/brick_region.h"

#include <bit>

namespace fremen::storage {

BoxBricks::BoxBricks(const CellBox& box, const std::array<uint32_t, 3>& brick_size) : box_(box), brick_size_(brick_size) {
  for (int a = 0; a < 3; ++a) {
    first_[a] = box.lo[a] / brick_size[a];
    count_[a] = box.hi[a] > box.lo[a] ? (box.hi[a] - 1) / brick_size[a] - first_[a] + 1 : 0;
  }
}

BrickLayout::BrickLayout(const GridKeys& keys) : size_(keys.brick_size()) {
  shift_y_ = static_cast<uint32_t>(std::countr_zero(size_[0]));
  shift_z_ = shift_y_ + static_cast<uint32_t>(std::countr_zero(size_[1]));
  for (uint32_t z = 0; z < size_[2]; ++z) {
    for (uint32_t y = 0; y < size_[1]; ++y) {
      for (uint32_t x = 0; x < size_[0]; ++x) {
        row_major_[keys.LocalIndex(x, y, z)] = static_cast<uint16_t>((z * size_[1] + y) * size_[0] + x);
      }
    }
  }
}

}  // namespace fremen::storage
