#include "storage/reconstruction_slots.h"

#include <gtest/gtest.h>

#include "storage/model/lossless/lossless_history.h"

namespace fremen::storage {
namespace {

constexpr uint64_t kMax = 1'000'000;
constexpr uint64_t kHeld = model::LosslessHistory::kMaxSlots;

// The slots of [start, end) on a map of `period`-second slots from `origin`, field by field.
void ExpectSlots(double origin, double period, double start, double end, const ReconstructionSlots& want) {
  const auto got = SlotsOfInterval(origin, period, start, end, kMax);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->count, want.count) << "[" << start << ", " << end << ")";
  EXPECT_EQ(got->first_time, want.first_time) << "[" << start << ", " << end << ")";
  EXPECT_EQ(got->begin, want.begin) << "[" << start << ", " << end << ")";
  EXPECT_EQ(got->end, want.end) << "[" << start << ", " << end << ")";
  EXPECT_EQ(got->offset, want.offset) << "[" << start << ", " << end << ")";
}

TEST(ReconstructionSlotsTest, EverySlotThatOverlapsTheInterval) {
  // Slots of 10 s from t = 100: [105, 131) overlaps slots 0 (100..110) to 3 (130..140).
  ExpectSlots(100, 10, 105, 131, {.count = 4, .first_time = 100, .begin = 0, .end = 4, .offset = 0});
  // Slot boundaries: [110, 130) is exactly slots 1 and 2.
  ExpectSlots(100, 10, 110, 130, {.count = 2, .first_time = 110, .begin = 1, .end = 3, .offset = 0});
}

TEST(ReconstructionSlotsTest, SlotsBeforeTheOriginAreAnsweredButNotHeld) {
  // [70, 125): slots −3..2; the history holds 0..2, at answer index 3.
  ExpectSlots(100, 10, 70, 125, {.count = 6, .first_time = 70, .begin = 0, .end = 3, .offset = 3});
  // Wholly before the origin: nothing held.
  ExpectSlots(100, 10, 20, 100, {.count = 8, .first_time = 20, .begin = 0, .end = 0, .offset = 0});
}

TEST(ReconstructionSlotsTest, SlotsPastTheLastAHistoryCanHoldAreNotHeld) {
  const double last = static_cast<double>(kHeld - 1);  // slot kHeld − 1 begins at t = last (origin 0, 1 s)
  ExpectSlots(0, 1, last, last + 5, {.count = 5, .first_time = last, .begin = kHeld - 1, .end = kHeld, .offset = 0});
  ExpectSlots(0, 1, last + 1, last + 3, {.count = 2, .first_time = last + 1, .begin = 0, .end = 0, .offset = 0});
}

TEST(ReconstructionSlotsTest, TooManySlotsIsInvalidArgument) {
  EXPECT_TRUE(SlotsOfInterval(0, 1, 0, 1'000'000, kMax).ok());
  const auto slots = SlotsOfInterval(0, 1, 0, 1'000'001, kMax);
  EXPECT_TRUE(absl::IsInvalidArgument(slots.status())) << slots.status();
  // An interval spanning more slots than an integer holds is refused, not cast.
  EXPECT_TRUE(absl::IsInvalidArgument(SlotsOfInterval(0, 1e-300, -1e13, 1e13, kMax).status()));
}

}  // namespace
}  // namespace fremen::storage
