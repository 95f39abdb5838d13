// Which lossless slots answer a reconstruction of [start_time, end_time) on a map that samples every
// `period` seconds from `origin` (docs/model.md, "Lossless history"): every slot that overlaps the
// interval, and the part of them a history can hold, [0, LosslessHistory::kMaxSlots) — slots before
// the origin or past the last possible slot are answered as unobserved.
// Thread-safety: a pure function.
#pragma once

#include <cstdint>

#include "absl/status/statusor.h"

namespace fremen::storage {

struct ReconstructionSlots {
  uint64_t count = 0;     // the slots overlapping [start_time, end_time): the answer's length per state
  double first_time = 0;  // when the first of them begins (before the origin when the interval is)
  // The slots a history holds, [begin, end) (empty when none overlaps), and where slot `begin`
  // stands in the answer.
  uint64_t begin = 0, end = 0;
  uint64_t offset = 0;
};

// REQUIRES: period > 0; start_time < end_time, both finite. InvalidArgument when the interval spans
// more than `max_slots` slots (at most 2^52, so that slot indices stay exact in a double).
absl::StatusOr<ReconstructionSlots> SlotsOfInterval(double origin, double period, double start_time,
                                                    double end_time, uint64_t max_slots);

}  // namespace fremen::storage
