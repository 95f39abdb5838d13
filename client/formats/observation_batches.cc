// Grouping observations into per-time batches (see observation_batches.h).
#include "client/formats/observation_batches.h"

#include <algorithm>
#include <numeric>

namespace fremen::formats {

std::vector<CellBatch> GroupByTime(const std::vector<CellObservation>& observations) {
  std::vector<size_t> order(observations.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return observations[a].t < observations[b].t; });
  std::vector<CellBatch> batches;
  for (size_t i : order) {
    const CellObservation& o = observations[i];
    if (batches.empty() || batches.back().time != o.t) {
      batches.emplace_back();
      batches.back().time = o.t;
    }
    batches.back().Add(o.x, o.y, o.z, o.s);
  }
  return batches;
}

}  // namespace fremen::formats
