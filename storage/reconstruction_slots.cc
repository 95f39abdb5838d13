#include "storage/reconstruction_slots.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "storage/model/lossless/lossless_history.h"

namespace fremen::storage {

absl::StatusOr<ReconstructionSlots> SlotsOfInterval(double origin, double period, double start_time,
                                                    double end_time, uint64_t max_slots) {
  const double s0 = std::floor((start_time - origin) / period);
  const double s1 = std::ceil((end_time - origin) / period);
  // Checked in double before any cast: the interval may span more slots than any integer holds.
  if (!(s1 - s0 <= static_cast<double>(max_slots))) {
    return absl::InvalidArgumentError(absl::StrCat("[start_time, end_time) spans ", s1 - s0, " slots of ", period,
                                                   " s; at most ", max_slots, " per call"));
  }
  ReconstructionSlots slots;
  slots.count = static_cast<uint64_t>(s1 - s0);
  slots.first_time = origin + s0 * period;
  constexpr double kHeld = static_cast<double>(model::LosslessHistory::kMaxSlots);
  if (!(s1 > 0 && s0 < kHeld)) return slots;  // no slot a history can hold
  // −max_slots < s0 < 2^30 here, so every cast below is exact.
  const int64_t first = static_cast<int64_t>(s0);
  slots.begin = static_cast<uint64_t>(std::max<int64_t>(first, 0));
  slots.end = std::min<uint64_t>(static_cast<uint64_t>(s1), model::LosslessHistory::kMaxSlots);
  slots.offset = static_cast<uint64_t>(static_cast<int64_t>(slots.begin) - first);
  return slots;
}

}  // namespace fremen::storage
