#include "storage/brick_region.h"

namespace fremen::storage {

BoxBricks::BoxBricks(const CellBox& box, const std::array<uint32_t, 3>& brick_size) : box_(box), brick_size_(brick_size) {
  for (int a = 0; a < 3; ++a) {
    first_[a] = box.lo[a] / brick_size[a];
    count_[a] = box.hi[a] > box.lo[a] ? (box.hi[a] - 1) / brick_size[a] - first_[a] + 1 : 0;
  }
}

BrickRegion::BrickRegion(const GridKeys& keys, uint64_t nx, uint64_t ny) : flat_(keys.flat()) {
  const std::array<uint32_t, 3> bs = keys.brick_size();
  for (uint32_t z = 0; z < bs[2]; ++z) {
    for (uint32_t y = 0; y < bs[1]; ++y) {
      for (uint32_t x = 0; x < bs[0]; ++x) {
        offset_[keys.LocalIndex(x, y, z)] = static_cast<int64_t>((uint64_t{z} * ny + y) * nx + x);
      }
    }
  }
  // See WriteSixteenAtATime: lanes 0 and 2 of v[0] and of the vector holding the block's other half.
  const uint32_t other_half = flat_ ? 8 : 4;
  row_start_ = {0, 2, other_half, other_half + 2};
}

}  // namespace fremen::storage
