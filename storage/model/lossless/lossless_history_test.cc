#include "storage/model/lossless/lossless_history.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "gtest/gtest.h"

namespace fremen::model {
namespace {

constexpr double kT0 = 1.7e9;      // an epoch time: phases must not lose precision there
constexpr double kDelta = 5.0;     // seconds per slot
constexpr uint64_t kDay = 17280;   // slots per day at 5 s

// The signal a test feeds in, slot by slot.
using Truth = std::vector<SlotState>;

Truth RandomTruth(uint64_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  Truth t(n);
  for (auto& s : t) s = (rng() & 1) ? SlotState::kOccupied : SlotState::kFree;
  return t;
}

// A daily square wave (occupied 08:00-18:00) with a share of slots flipped, unobserved 02:00-04:00
// every day and for a whole day now and then: the shape of an office door.
Truth PeriodicTruth(uint64_t n, double flip_share, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution flip(flip_share);
  Truth t(n);
  for (uint64_t i = 0; i < n; ++i) {
    const uint64_t day = i / kDay;
    const uint64_t hour = (i % kDay) / 720;
    if ((hour >= 2 && hour < 4) || day % 9 == 5) {
      t[i] = SlotState::kUnobserved;
      continue;
    }
    const bool occupied = (hour >= 8 && hour < 18) != flip(rng);
    t[i] = occupied ? SlotState::kOccupied : SlotState::kFree;
  }
  return t;
}

Truth NoiseTruth(uint64_t n, double p_one, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution one(p_one);
  Truth t(n);
  for (auto& s : t) s = one(rng) ? SlotState::kOccupied : SlotState::kFree;
  return t;
}

LosslessHistory NewHistory() { return *LosslessHistory::Create(kT0, kDelta); }

// Adds truth[begin, end) by time, at the middle of each slot.
void AddRange(LosslessHistory& h, const Truth& truth, uint64_t begin, uint64_t end) {
  for (uint64_t i = begin; i < end; ++i) {
    if (truth[i] == SlotState::kUnobserved) continue;
    const float s = truth[i] == SlotState::kOccupied ? 1.0f : 0.0f;
    ASSERT_TRUE(h.Add(kT0 + (static_cast<double>(i) + 0.5) * kDelta, s).ok());
  }
}

// Reconstruction of [0, truth.size()) equals the truth slot for slot; the first difference is reported.
void ExpectExact(const LosslessHistory& h, const Truth& truth) {
  const absl::StatusOr<Truth> got = h.Reconstruct(0, truth.size());
  ASSERT_TRUE(got.ok()) << got.status();
  for (size_t i = 0; i < truth.size(); ++i) {
    ASSERT_EQ(static_cast<int>((*got)[i]), static_cast<int>(truth[i])) << "slot " << i;
  }
}

// ε over observed slots in [begin, end), counted directly from P and the truth.
LosslessHistory::Error DirectError(const LosslessHistory& h, const Truth& truth, uint64_t begin, uint64_t end) {
  LosslessHistory::Error e;
  for (uint64_t i = begin; i < end && i < truth.size(); ++i) {
    if (truth[i] == SlotState::kUnobserved) continue;
    ++e.observed;
    e.wrong += h.model().SlotEstimate(i) != (truth[i] == SlotState::kOccupied);
  }
  return e;
}

void ExpectErrorsFromOutliersMatchDirectCounts(const LosslessHistory& h, const Truth& truth) {
  const uint64_t m = h.slot_count();
  const LosslessHistory::Error ee = h.EstimationError(), de = DirectError(h, truth, 0, m);
  EXPECT_EQ(ee.wrong, de.wrong);
  EXPECT_EQ(ee.observed, de.observed);
  const LosslessHistory::Error ep = h.PredictionError(), dp = DirectError(h, truth, h.update_slot(), m);
  EXPECT_EQ(ep.wrong, dp.wrong);
  EXPECT_EQ(ep.observed, dp.observed);
  // An arbitrary window by eq. 15.
  const LosslessHistory::Error ew = h.ErrorBetween(m / 3, m / 2), dw = DirectError(h, truth, m / 3, m / 2);
  EXPECT_EQ(ew.wrong, dw.wrong);
  EXPECT_EQ(ew.observed, dw.observed);
}

TEST(LosslessHistory, RandomSignalOfAMillionSlotsIsExactBeforeAndAfterUpdate) {
  const uint64_t n = 1'000'000, more = 100'000;
  const Truth truth = RandomTruth(n + more, 1);
  LosslessHistory h = NewHistory();
  AddRange(h, truth, 0, n);
  EXPECT_EQ(h.slot_count(), n);
  Truth seen(truth.begin(), truth.begin() + n);
  ExpectExact(h, seen);
  ExpectErrorsFromOutliersMatchDirectCounts(h, seen);

  ASSERT_TRUE(h.Update(5).ok());
  ExpectExact(h, seen);
  ExpectErrorsFromOutliersMatchDirectCounts(h, seen);
  EXPECT_EQ(h.update_slot(), n);

  AddRange(h, truth, n, n + more);
  ExpectExact(h, truth);
  ExpectErrorsFromOutliersMatchDirectCounts(h, truth);
  ASSERT_TRUE(h.Update(5).ok());
  ExpectExact(h, truth);
}

TEST(LosslessHistory, PeriodicSignalWithNoiseAndGapsIsExactBeforeAndAfterUpdate) {
  const uint64_t n = 1'000'000;
  const Truth truth = PeriodicTruth(n, 0.05, 2);
  LosslessHistory h = NewHistory();
  const uint64_t first_part = 40 * kDay;
  AddRange(h, truth, 0, first_part);
  Truth seen(truth.begin(), truth.begin() + first_part);
  ExpectExact(h, seen);
  // Before the first update P predicts 0: O holds the occupied runs, ε_e is the share of ones.
  EXPECT_GT(h.EstimationError().rate(), 0.3);

  const absl::StatusOr<int> order = h.Update(5);
  ASSERT_TRUE(order.ok()) << order.status();
  EXPECT_GE(*order, 1);
  ExpectExact(h, seen);
  ExpectErrorsFromOutliersMatchDirectCounts(h, seen);
  // The model explains the square wave: O is left with (about) the 5% flips.
  EXPECT_NEAR(h.EstimationError().rate(), 0.05, 0.01);

  AddRange(h, truth, first_part, n);
  ExpectExact(h, truth);
  ExpectErrorsFromOutliersMatchDirectCounts(h, truth);
  EXPECT_NEAR(h.PredictionError().rate(), 0.05, 0.01);
  ASSERT_TRUE(h.Update(5).ok());
  ExpectExact(h, truth);
  ExpectErrorsFromOutliersMatchDirectCounts(h, truth);

  const LosslessHistory::Compression c = h.CompressionFigures();
  EXPECT_EQ(c.raw_bits, n);
  EXPECT_EQ(c.model_bytes, h.model().encoded_size());
  EXPECT_EQ(c.outlier_bytes, h.outliers().encoded_size());
  EXPECT_EQ(c.record_bytes, h.Encode().size());
  EXPECT_GT(c.ratio(), 1.0);
  // Sub-ranges, small (direct phasors) and large (tables), and past the end.
  for (auto [a, b] : {std::pair<uint64_t, uint64_t>{12345, 12400}, {kDay * 3 + 7, kDay * 10 + 3}, {n - 50, n + 50}}) {
    const Truth part = *h.Reconstruct(a, b);
    for (uint64_t i = a; i < b; ++i) {
      ASSERT_EQ(static_cast<int>(part[i - a]), static_cast<int>(i < n ? truth[i] : SlotState::kUnobserved)) << i;
    }
  }
}

TEST(LosslessHistory, LatestObservationOfASlotWinsAnywhereInTheHistory) {
  std::mt19937_64 rng(3);
  const uint64_t n = 20 * kDay;
  Truth truth = PeriodicTruth(n, 0.05, 4);
  LosslessHistory h = NewHistory();
  AddRange(h, truth, 0, n / 2);
  ASSERT_TRUE(h.Update(4).ok());
  AddRange(h, truth, n / 2, n);
  // Re-observations with new values, late observations of gaps, and the newest slot again and again.
  for (int i = 0; i < 20000; ++i) {
    uint64_t slot = i % 4 == 0 ? n - 1 : rng() % n;
    const bool s = rng() & 1;
    ASSERT_TRUE(h.AddSlot(slot, s).ok());
    truth[slot] = s ? SlotState::kOccupied : SlotState::kFree;
    if (i % 5000 == 0) ExpectExact(h, truth);
  }
  ExpectExact(h, truth);
  ExpectErrorsFromOutliersMatchDirectCounts(h, truth);
  ASSERT_TRUE(h.Update(4).ok());
  ExpectExact(h, truth);
  ExpectErrorsFromOutliersMatchDirectCounts(h, truth);
}

TEST(LosslessHistory, SoftValuesAreThresholdedAndTimesMapToSlots) {
  LosslessHistory h = NewHistory();
  ASSERT_TRUE(h.Add(kT0, 0.7f).ok());                  // slot 0
  ASSERT_TRUE(h.Add(kT0 + 2 * kDelta + 4.9, 0.2f).ok());  // slot 2
  ASSERT_TRUE(h.Add(kT0 + 3 * kDelta, 0.5f).ok());     // slot 3
  EXPECT_EQ(*h.SlotOf(kT0 + 2 * kDelta + 4.9), 2u);
  EXPECT_EQ(h.slot_count(), 4u);
  EXPECT_EQ(h.observed_count(), 3u);
  EXPECT_EQ(*h.Reconstruct(0, 6), (Truth{SlotState::kOccupied, SlotState::kUnobserved, SlotState::kFree,
                                         SlotState::kOccupied, SlotState::kUnobserved, SlotState::kUnobserved}));
}

TEST(LosslessHistory, OrderSelectionPrefersStructureOnPeriodicDataAndNothingOnNoise) {
  const uint64_t first = 14 * kDay, n = 21 * kDay;
  {
    const Truth truth = PeriodicTruth(n, 0.05, 5);
    LosslessHistory h = NewHistory();
    AddRange(h, truth, 0, first);
    const absl::StatusOr<int> initial = h.Update(5);
    ASSERT_TRUE(initial.ok());
    EXPECT_GE(*initial, 1);
    AddRange(h, truth, first, n);
    const absl::StatusOr<int> chosen = h.Update(5);  // scored on the last week, which P predicted
    ASSERT_TRUE(chosen.ok());
    EXPECT_GE(*chosen, 1);
    EXPECT_EQ(h.model().order(), *chosen);
  }
  {
    const Truth truth = NoiseTruth(n, 0.3, 6);
    LosslessHistory h = NewHistory();
    AddRange(h, truth, 0, first);
    const absl::StatusOr<int> initial = h.Update(5);
    ASSERT_TRUE(initial.ok());
    EXPECT_EQ(*initial, 0);
    AddRange(h, truth, first, n);
    const absl::StatusOr<int> chosen = h.Update(5);
    ASSERT_TRUE(chosen.ok());
    EXPECT_EQ(*chosen, 0);
    ExpectExact(h, truth);
  }
}

TEST(LosslessHistory, FixedOrderAndUpdatesWithoutNewData) {
  const uint64_t n = 10 * kDay;
  const Truth truth = PeriodicTruth(n, 0.02, 7);
  LosslessHistory h = NewHistory();
  AddRange(h, truth, 0, n);
  EXPECT_EQ(*h.Update(5, 2), 2);
  EXPECT_EQ(h.model().order(), 2);
  EXPECT_EQ(h.model().components().size(), 5u);
  // Nothing observed since: the order stays.
  EXPECT_EQ(*h.Update(5), 2);
  ExpectExact(h, truth);
  EXPECT_EQ(h.PredictionError().observed, 0u);
  EXPECT_EQ(*h.Update(0), 0);
  EXPECT_TRUE(h.model().components().empty());
  ExpectExact(h, truth);
}

// P as Update publishes it for `h` by docs/model.md's rule, computed from every reconstructed slot:
// the reference the update of a constant history, which reconstructs none, must match.
BinModel ModelFromSlots(const LosslessHistory& h, int max_order) {
  const uint64_t m = h.slot_count();
  const Truth signal = *h.Reconstruct(0, m);
  std::vector<uint64_t> errors(max_order + 1, 0);
  const bool can_predict = !h.model().components().empty();
  const bool seen_since = h.coverage().Count(h.update_slot(), m) > 0;
  if (can_predict && seen_since) {
    SlotPredictor(h.model()).CountErrors(h.update_slot(), std::span(signal).subspan(h.update_slot()), errors);
  }
  BinModel next = BinModel::FromSpectrum(SlotSpectrum::Compute(signal), m - 1 - h.coverage().first_point(), max_order);
  if (!can_predict) SlotPredictor(next).CountErrors(0, signal, errors);
  const int chosen = can_predict && !seen_since
                         ? h.model().order()
                         : static_cast<int>(std::min_element(errors.begin(), errors.end()) - errors.begin());
  next.set_order(std::min<int>(chosen, static_cast<int>(next.components().size())));
  return next;
}

// Updates `h` and checks it against ModelFromSlots and the truth (of which h holds a prefix).
void ExpectUpdateMatchesTheSlots(LosslessHistory& h, const Truth& truth, int max_order) {
  const BinModel expected = ModelFromSlots(h, max_order);
  ASSERT_TRUE(h.Update(max_order).ok());
  EXPECT_EQ(h.model(), expected);
  EXPECT_EQ(h.update_slot(), h.slot_count());
  const Truth held(truth.begin(), truth.begin() + h.slot_count());
  ExpectExact(h, held);
  ExpectErrorsFromOutliersMatchDirectCounts(h, held);
}

// Every observed slot `value`, with the gaps of PeriodicTruth.
Truth ConstantTruth(uint64_t n, bool value) {
  Truth t = PeriodicTruth(n, 0, 1);
  for (SlotState& s : t) {
    if (s != SlotState::kUnobserved) s = value ? SlotState::kOccupied : SlotState::kFree;
  }
  return t;
}

TEST(LosslessHistory, ConstantHistoriesUpdateFromTheirTogglePointsAsFromTheirSlots) {
  for (const bool value : {true, false}) {
    SCOPED_TRACE(value ? "occupied" : "free");
    const uint64_t n = 12 * kDay;
    const Truth truth = ConstantTruth(n, value);
    LosslessHistory h = NewHistory();
    AddRange(h, truth, 0, 10 * kDay);
    ExpectUpdateMatchesTheSlots(h, truth, 5);  // the first: P had no components
    EXPECT_EQ(h.model().alpha0(), value ? 1.0f : 0.0f);
    EXPECT_TRUE(h.model().IsConstant());
    EXPECT_TRUE(h.outliers().empty());
    ExpectUpdateMatchesTheSlots(h, truth, 5);  // nothing new
    AddRange(h, truth, 10 * kDay, n);
    ExpectUpdateMatchesTheSlots(h, truth, 5);  // a new day, scored by zero-amplitude components
    ExpectUpdateMatchesTheSlots(h, truth, 0);
  }
}

TEST(LosslessHistory, AHistoryMadeConstantByLateObservationsUpdatesAsFromItsSlots) {
  // A dynamic history whose differing slots are all observed again as occupied: P still has
  // components (at order 0 they are not used by the estimate, but they are scored).
  const uint64_t n = 6 * kDay;
  Truth truth = PeriodicTruth(n, 0.02, 3);
  LosslessHistory h = NewHistory();
  AddRange(h, truth, 0, 4 * kDay);
  ASSERT_TRUE(h.Update(5, 0).ok());
  ASSERT_FALSE(h.model().IsConstant(5));
  for (SlotState& s : truth) {
    if (s == SlotState::kFree) s = SlotState::kOccupied;
  }
  AddRange(h, truth, 0, n);
  ExpectUpdateMatchesTheSlots(h, truth, 5);
  EXPECT_TRUE(h.outliers().empty());
  // And at an order above 0, where the estimate itself varies: the ordinary path.
  Truth dynamic = PeriodicTruth(n, 0.02, 4);
  LosslessHistory d = NewHistory();
  AddRange(d, dynamic, 0, 4 * kDay);
  ASSERT_TRUE(d.Update(5, 3).ok());
  for (SlotState& s : dynamic) {
    if (s == SlotState::kOccupied) s = SlotState::kFree;
  }
  AddRange(d, dynamic, 0, n);
  ExpectUpdateMatchesTheSlots(d, dynamic, 5);
  EXPECT_TRUE(d.outliers().empty());
}

TEST(LosslessHistory, UpdateOfAnEmptyHistoryChangesNothing) {
  LosslessHistory h = NewHistory();
  EXPECT_EQ(*h.Update(5), 0);
  EXPECT_EQ(h, NewHistory());
  EXPECT_TRUE(h.Reconstruct(0, 10)->size() == 10);
  EXPECT_EQ(h.EstimationError().rate(), 0.0);
}

TEST(LosslessHistory, RejectsBadArguments) {
  EXPECT_EQ(LosslessHistory::Create(NAN, 1).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(LosslessHistory::Create(0, 0).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(LosslessHistory::Create(0, -1).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(LosslessHistory::Create(0, INFINITY).status().code(), absl::StatusCode::kInvalidArgument);
  LosslessHistory h = NewHistory();
  EXPECT_EQ(h.Add(kT0 - 1, 1).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Add(NAN, 1).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Add(kT0, 1.5f).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Add(kT0, NAN).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Add(kT0 + kDelta * static_cast<double>(LosslessHistory::kMaxSlots), 1).code(),
            absl::StatusCode::kOutOfRange);
  EXPECT_EQ(h.AddSlot(LosslessHistory::kMaxSlots, true).code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(h.Update(-1).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Update(65).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Update(3, 4).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Reconstruct(5, 4).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h.Reconstruct(0, LosslessHistory::kMaxSlots + 1).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(h, NewHistory());  // nothing was recorded
  // The far future is fine below the limit, and extends m.
  ASSERT_TRUE(h.AddSlot(LosslessHistory::kMaxSlots - 1, true).ok());
  EXPECT_EQ(h.slot_count(), LosslessHistory::kMaxSlots);
}

LosslessHistory SampleHistory() {
  const uint64_t n = 3 * kDay;
  const Truth truth = PeriodicTruth(n, 0.05, 8);
  LosslessHistory h = NewHistory();
  AddRange(h, truth, 0, 2 * kDay);
  EXPECT_TRUE(h.Update(5).ok());
  AddRange(h, truth, 2 * kDay, n);
  return h;
}

TEST(LosslessHistory, EncodingRoundTrips) {
  const LosslessHistory h = SampleHistory();
  const std::string bytes = h.Encode();
  EXPECT_EQ(bytes.size(), h.encoded_size());
  EXPECT_EQ(bytes[0], static_cast<char>(LosslessHistory::kFormatVersion));
  const absl::StatusOr<LosslessHistory> decoded = LosslessHistory::Decode(bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, h);
  EXPECT_EQ(*decoded->Reconstruct(0, h.slot_count()), *h.Reconstruct(0, h.slot_count()));
  EXPECT_EQ(decoded->Encode(), bytes);
  const absl::StatusOr<LosslessHistory> empty = LosslessHistory::Decode(NewHistory().Encode());
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_EQ(*empty, NewHistory());
}

TEST(LosslessHistory, DecodeNamesWhatIsWrong) {
  const std::string good = SampleHistory().Encode();
  std::string bad_version = good;
  bad_version[0] = 7;
  EXPECT_NE(LosslessHistory::Decode(bad_version).status().message().find("version: unsupported version 7"),
            std::string::npos);
  EXPECT_NE(LosslessHistory::Decode("").status().message().find("version: truncated"), std::string::npos);
  std::string bad_delta = good;
  for (int i = 9; i < 17; ++i) bad_delta[i] = 0;  // Δ = 0.0
  EXPECT_NE(LosslessHistory::Decode(bad_delta).status().message().find("delta"), std::string::npos);
  EXPECT_EQ(LosslessHistory::Decode(good + "x").status().code(), absl::StatusCode::kDataLoss);
}

TEST(LosslessHistory, FuzzedEncodingsAreRejectedOrConsistentNeverACrash) {
  const std::string good = SampleHistory().Encode();
  std::mt19937_64 rng(12);
  int rejected = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    std::string bytes = good;
    switch (trial % 3) {
      case 0:
        bytes.resize(rng() % bytes.size());
        break;
      case 1:
        for (int flips = 1 + rng() % 4; flips > 0; --flips) bytes[rng() % bytes.size()] ^= static_cast<char>(1 << (rng() % 8));
        break;
      default:
        // Corrupt the header and model region, where the structure is densest.
        bytes[rng() % std::min<size_t>(bytes.size(), 80)] = static_cast<char>(rng());
    }
    const absl::StatusOr<LosslessHistory> decoded = LosslessHistory::Decode(bytes);
    if (!decoded.ok()) {
      EXPECT_EQ(decoded.status().code(), absl::StatusCode::kDataLoss);
      EXPECT_NE(decoded.status().message().find("lossless history: "), std::string::npos);
      ++rejected;
      continue;
    }
    // Whatever decodes is a usable history.
    EXPECT_EQ(decoded->Encode(), bytes);
    const uint64_t m = decoded->slot_count();
    EXPECT_TRUE(decoded->Reconstruct(m > 5000 ? m - 5000 : 0, m).ok());
    (void)decoded->EstimationError();
  }
  EXPECT_GT(rejected, 1000);
}

}  // namespace
}  // namespace fremen::model
