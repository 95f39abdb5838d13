#include "storage/reconstruction_slots.h"

#include <gtest/gtest.h>

#include "storage/model/lossless_history.h"

namespace fremen::storage {
namespace {

constexpr uint64_t kMax = 1'000'000;
constexpr uint64_t kHeld = model::LosslessHistory::kMaxSlots;

TEST(ReconstructionSlotsTest, EverySlotThatOverlapsTheInterval) {
  // Slots of 10 s from t = 100: [105, 131) overlaps slots 0 (100..110) to 3 (130..140).
  auto slots = SlotsOfInterval(100, 10, 105, 131, kMax);
  ASSERT_TRUE(slots.ok()) << slots.status();
  EXPECT_EQ(slots->count, 4u);
  EXPECT_EQ(slots->first_time, 100.0);
  EXPECT_EQ(slots->begin, 0u);
  EXPECT_EQ(slots->end, 4u);
  EXPECT_EQ(slots->offset, 0u);
  // Slot boundaries: [110, 130) is exactly slots 1 and 2.
  slots = SlotsOfInterval(100, 10, 110, 130, kMax);
  ASSERT_TRUE(slots.ok());
  EXPECT_EQ(slots->count, 2u);
  EXPECT_EQ(slots->first_time, 110.0);
  EXPECT_EQ(slots->begin, 1u);
  EXPECT_EQ(slots->end, 3u);
  EXPECT_EQ(slots->offset, 0u);
}

TEST(ReconstructionSlotsTest, SlotsBeforeTheOriginAreAnsweredButNotHeld) {
  // [70, 125): slots −3..2; the history holds 0..2, at answer index 3.
  auto slots = SlotsOfInterval(100, 10, 70, 125, kMax);
  ASSERT_TRUE(slots.ok());
  EXPECT_EQ(slots->count, 6u);
  EXPECT_EQ(slots->first_time, 70.0);
  EXPECT_EQ(slots->begin, 0u);
  EXPECT_EQ(slots->end, 3u);
  EXPECT_EQ(slots->offset, 3u);
  // Wholly before the origin: nothing held.
  slots = SlotsOfInterval(100, 10, 20, 100, kMax);
  ASSERT_TRUE(slots.ok());
  EXPECT_EQ(slots->count, 8u);
  EXPECT_EQ(slots->begin, slots->end);
}

TEST(ReconstructionSlotsTest, SlotsPastTheLastAHistoryCanHoldAreNotHeld) {
  const double last = static_cast<double>(kHeld - 1);  // slot kHeld − 1 begins at t = last (origin 0, 1 s)
  auto slots = SlotsOfInterval(0, 1, last, last + 5, kMax);
  ASSERT_TRUE(slots.ok());
  EXPECT_EQ(slots->count, 5u);
  EXPECT_EQ(slots->begin, kHeld - 1);
  EXPECT_EQ(slots->end, kHeld);
  EXPECT_EQ(slots->offset, 0u);
  slots = SlotsOfInterval(0, 1, last + 1, last + 3, kMax);
  ASSERT_TRUE(slots.ok());
  EXPECT_EQ(slots->count, 2u);
  EXPECT_EQ(slots->begin, slots->end);
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
