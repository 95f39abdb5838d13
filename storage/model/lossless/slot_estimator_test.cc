#include "storage/model/lossless/slot_estimator.h"

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "storage/model/lossless/bin_spectrum.h"
#include "storage/model/varint.h"

namespace fremen::model {
namespace {

// A model with exactly these coefficients, through its record (the only way to set them).
BinModel MakeModel(uint64_t n, float alpha0, const std::vector<BinComponent>& components, int order) {
  std::string bytes;
  PutVarint64(&bytes, n);
  PutFloat(&bytes, alpha0);
  bytes.push_back(static_cast<char>(order));
  PutVarint64(&bytes, components.size());
  for (const BinComponent& c : components) {
    PutVarint64(&bytes, c.k);
    PutFloat(&bytes, c.a);
    PutFloat(&bytes, c.b);
  }
  ByteReader reader(bytes, "test");
  BinModel model = BinModel::Decode(reader, "model");
  EXPECT_TRUE(reader.Finish().ok());
  return model;
}

// Compares the estimates of slots [begin, begin + count) with SlotValue ≥ 0.5 slot by slot;
// returns how many the estimator evaluated exactly.
size_t ExpectEstimatesMatchSlotValues(const BinModel& model, uint64_t begin, size_t count) {
  const SlotEstimator estimator(model);
  std::unique_ptr<bool[]> got(new bool[count]);
  const size_t exact = estimator.Estimates(begin, std::span<bool>(got.get(), count));
  for (size_t i = 0; i < count; ++i) {
    const bool expected = model.SlotValue(begin + i) >= 0.5;
    if (got[i] != expected) {
      ADD_FAILURE() << "slot " << begin + i << ": estimate " << got[i] << ", SlotValue "
                    << model.SlotValue(begin + i);
      break;
    }
  }
  return exact;
}

TEST(LosslessSlotEstimator, AgreesWithSlotValueOnRandomModels) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> unit(0, 1), coefficient(-0.6f, 0.6f);
  for (int trial = 0; trial < 300; ++trial) {
    const uint64_t n = 2 + rng() % (trial < 150 ? 5000 : 3'000'000);
    const int held = 1 + static_cast<int>(rng() % 8);
    std::vector<BinComponent> components;
    for (int j = 0; j < held; ++j) {
      components.push_back({static_cast<uint32_t>(1 + rng() % (n / 2)), coefficient(rng), coefficient(rng)});
    }
    const BinModel model = MakeModel(n, unit(rng), components, static_cast<int>(rng() % (held + 1)));
    // Anywhere, beyond n too (a model is evaluated on the slots observed after it), odd lengths.
    const uint64_t begin = rng() % (3 * n);
    ExpectEstimatesMatchSlotValues(model, begin, 1 + rng() % 9000);
    if (HasFailure()) return;
  }
}

TEST(LosslessSlotEstimator, AgreesWithSlotValueOnAModelOfADailyRhythm) {
  // What the update evaluates: the strongest bins of a noisy daily square wave, 20 days of 5-s
  // slots; p crosses 0.5 twice a day and wanders near it in between.
  constexpr uint64_t kDay = 17280, n = 20 * kDay;
  std::mt19937_64 rng(3);
  std::vector<SlotState> signal(n);
  for (uint64_t i = 0; i < n; ++i) {
    const bool day = (i % kDay) > kDay / 3 && (i % kDay) < 2 * kDay / 3;
    signal[i] = day != (rng() % 50 == 0) ? SlotState::kOccupied : SlotState::kFree;
  }
  const BinModel model = BinModel::FromSpectrum(SlotSpectrum::Compute(signal), n - 1, 16);
  ASSERT_EQ(model.order(), 16);
  const size_t exact = ExpectEstimatesMatchSlotValues(model, 0, n + kDay);
  // The exact fallback is for the rare slot near 0.5, not the rule.
  EXPECT_LT(exact, n / 1000);
}

TEST(LosslessSlotEstimator, SlotsOfExactlyOneHalfAreDecidedBySlotValue) {
  // α0 = 0.5 and a quarter-turn component: cos(πi/2) is exactly 0 at every odd slot, so p is 0.5
  // there, and 0.25 or 0.75 at even slots.
  const BinModel model = MakeModel(64, 0.5f, {{16, 0.25f, 0.0f}}, 1);
  EXPECT_GE(ExpectEstimatesMatchSlotValues(model, 0, 640), 320u);
  EXPECT_GE(ExpectEstimatesMatchSlotValues(model, 7, 5), 2u);
  // Near 0.5 by less than the bound, either side.
  for (const float alpha0 : {0.5f + 1e-7f, 0.5f - 1e-7f}) {
    const BinModel near = MakeModel(1000, alpha0, {{3, 1e-8f, -1e-8f}}, 1);
    EXPECT_EQ(ExpectEstimatesMatchSlotValues(near, 0, 1000), 0u);  // 1e-7 is far beyond 1e-9·scale
  }
  const BinModel nearer = MakeModel(1000, 0.5f, {{3, 1e-12f, 1e-12f}}, 1);
  EXPECT_EQ(ExpectEstimatesMatchSlotValues(nearer, 0, 1000), 1000u);
}

TEST(LosslessSlotEstimator, AModelWithoutComponentsOrWithZeroAmplitudesIsItsMean) {
  for (const float alpha0 : {0.0f, 0.4999999f, 0.5f, 1.0f}) {
    EXPECT_EQ(ExpectEstimatesMatchSlotValues(MakeModel(100, alpha0, {}, 0), 0, 300), 0u);
    EXPECT_EQ(ExpectEstimatesMatchSlotValues(MakeModel(100, alpha0, {{5, 0.0f, -0.0f}}, 1), 0, 300), 0u);
    // Components held but not used at order 0.
    EXPECT_EQ(ExpectEstimatesMatchSlotValues(MakeModel(100, alpha0, {{5, 0.3f, 0.2f}}, 0), 5, 300), 0u);
  }
}

}  // namespace
}  // namespace fremen::model
