#include "server/services/region_plan.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "storage/model/published_model.h"

namespace fremen::server {

namespace {

uint64_t CeilDiv(uint64_t a, uint64_t b) { return (a + b - 1) / b; }

}  // namespace

absl::StatusOr<storage::CellBox> RegionBoxOf(const storage::MapInfo& map, const v1::CellIndex& lo,
                                             const v1::CellIndex& hi) {
  if (map.kind != storage::MapKind::kGrid) {
    return absl::FailedPreconditionError(absl::StrCat("map ", map.name, " is not a grid: it has no regions"));
  }
  storage::CellBox box;
  box.lo = {lo.x(), lo.y(), lo.z()};
  box.hi = {hi.x(), hi.y(), hi.z()};
  if (map.grid.size[2] == 1 && box.lo[2] == 0 && box.hi[2] == 0) box.hi[2] = 1;
  static constexpr const char* kAxes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (box.hi[a] > map.grid.size[a]) {
      return absl::OutOfRangeError(absl::StrCat("hi.", kAxes[a], " must be ≤ ", map.grid.size[a],
                                                " (the size of map ", map.name, " along ", kAxes[a], "), got ",
                                                box.hi[a]));
    }
    if (box.lo[a] >= box.hi[a]) {
      return absl::OutOfRangeError(absl::StrCat("lo.", kAxes[a], " must be < hi.", kAxes[a], " (the box [lo, hi) ",
                                                "must not be empty), got lo.", kAxes[a], " = ", box.lo[a], ", hi.",
                                                kAxes[a], " = ", box.hi[a]));
    }
  }
  return box;
}

absl::StatusOr<v1::RegionOutput> RegionOutputOf(int output) {
  if (output == v1::REGION_OUTPUT_UNSPECIFIED) return v1::REGION_OUTPUT_FLOAT;
  if (!v1::RegionOutput_IsValid(output)) {
    return absl::InvalidArgumentError(absl::StrCat("output ", output, " is not a RegionOutput"));
  }
  return static_cast<v1::RegionOutput>(output);
}

uint64_t BytesPerCell(v1::RegionOutput output) {
  return output == v1::REGION_OUTPUT_UINT8 || output == v1::REGION_OUTPUT_STATES ? 1 : 4;
}

uint64_t ChunkCells(uint64_t requested, v1::RegionOutput output) {
  const uint64_t most = kMaxChunkBytes / BytesPerCell(output);
  return requested == 0 ? most : std::min(requested, most);
}

uint64_t BaseChunkCells(uint64_t max_cells, v1::RegionOutput output) {
  // At most 8·B + 1 bits a cell: its value (when constant) and its bit of the mask.
  const uint64_t fit = kMaxChunkBytes * 8 / (8 * BytesPerCell(output) + 1);
  return std::max<uint64_t>(8, std::min(max_cells, fit) / 8 * 8);
}

RegionPlan::RegionPlan(const storage::CellBox& box, uint64_t max_cells)
    : box_(box), nx_(box.hi[0] - box.lo[0]), ny_(box.hi[1] - box.lo[1]), nz_(box.hi[2] - box.lo[2]) {
  if (nx_ * ny_ <= max_cells) {
    unit_ = Unit::kPlanes;
    per_ = max_cells / (nx_ * ny_);
    per_line_ = 1;
    count_ = CeilDiv(nz_, per_);
  } else if (nx_ <= max_cells) {
    unit_ = Unit::kRows;
    per_ = max_cells / nx_;
    per_line_ = CeilDiv(ny_, per_);
    count_ = nz_ * per_line_;
  } else {
    unit_ = Unit::kRowParts;
    per_ = max_cells;
    per_line_ = CeilDiv(nx_, per_);
    count_ = nz_ * ny_ * per_line_;
  }
}

RegionPlan::Chunk RegionPlan::chunk(uint64_t i) const {
  Chunk c;
  c.box = box_;
  const auto u32 = [](uint64_t v) { return static_cast<uint32_t>(v); };
  switch (unit_) {
    case Unit::kPlanes: {
      const uint64_t z0 = i * per_;
      c.box.lo[2] = u32(box_.lo[2] + z0);
      c.box.hi[2] = u32(std::min<uint64_t>(box_.hi[2], box_.lo[2] + z0 + per_));
      c.offset = z0 * nx_ * ny_;
      break;
    }
    case Unit::kRows: {
      const uint64_t z = i / per_line_, y0 = (i % per_line_) * per_;
      c.box.lo[2] = u32(box_.lo[2] + z);
      c.box.hi[2] = c.box.lo[2] + 1;
      c.box.lo[1] = u32(box_.lo[1] + y0);
      c.box.hi[1] = u32(std::min<uint64_t>(box_.hi[1], box_.lo[1] + y0 + per_));
      c.offset = (z * ny_ + y0) * nx_;
      break;
    }
    case Unit::kRowParts: {
      const uint64_t row = i / per_line_, x0 = (i % per_line_) * per_;
      c.box.lo[2] = u32(box_.lo[2] + row / ny_);
      c.box.hi[2] = c.box.lo[2] + 1;
      c.box.lo[1] = u32(box_.lo[1] + row % ny_);
      c.box.hi[1] = c.box.lo[1] + 1;
      c.box.lo[0] = u32(box_.lo[0] + x0);
      c.box.hi[0] = u32(std::min<uint64_t>(box_.hi[0], box_.lo[0] + x0 + per_));
      c.offset = row * nx_ + x0;
      break;
    }
  }
  return c;
}

void EncodeRegionValues(v1::RegionOutput output, float confidence, std::span<const float> p,
                        google::protobuf::RepeatedField<float>& floats, std::string& bytes) {
  floats.Clear();
  bytes.clear();
  switch (output) {
    case v1::REGION_OUTPUT_ENTROPY: {
      auto& values = floats;
      values.Reserve(static_cast<int>(p.size()));
      for (float v : p) values.AddAlreadyReserved(static_cast<float>(model::Entropy(v)));
      return;
    }
    case v1::REGION_OUTPUT_UINT8:
    case v1::REGION_OUTPUT_STATES: {
      bytes.resize(p.size());
      auto* b = reinterpret_cast<uint8_t*>(bytes.data());
      if (output == v1::REGION_OUTPUT_UINT8) {
        // p is clamped to [0, 1], so round(255·p) is the truncation of 255·p + 0.5.
        for (size_t i = 0; i < p.size(); ++i) b[i] = static_cast<uint8_t>(p[i] * 255.0f + 0.5f);
      } else {
        for (size_t i = 0; i < p.size(); ++i) b[i] = model::EstimateState(p[i], confidence) ? 1 : 0;
      }
      return;
    }
    default:  // FLOAT (the caller normalised UNSPECIFIED)
      floats.Add(p.begin(), p.end());
      return;
  }
}

}  // namespace fremen::server
