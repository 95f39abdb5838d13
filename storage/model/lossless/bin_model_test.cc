// Tests of the lossless history's building blocks: bin phasors, the FFT spectrum, the bin model.
#include "storage/model/lossless/bin_model.h"

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "storage/model/lossless/bin_phasor.h"
#include "storage/model/lossless/bin_spectrum.h"

namespace fremen::model {
namespace {

TEST(LosslessBinPhasor, MatchesLibmWithinAFewUlp) {
  std::mt19937_64 rng(5);
  for (uint64_t n : {1ull, 2ull, 3ull, 7ull, 64ull, 1000ull, 17280ull, 518400ull, 1000003ull, (1ull << 31) - 1}) {
    for (int i = 0; i < 2000; ++i) {
      const uint64_t r = rng() % n;
      const UnitPhasor p = BinPhasor(r, n);
      const long double angle = 2.0L * std::numbers::pi_v<long double> * r / n;
      EXPECT_NEAR(p.cos, static_cast<double>(std::cos(angle)), 4e-16) << r << "/" << n;
      EXPECT_NEAR(p.sin, static_cast<double>(std::sin(angle)), 4e-16) << r << "/" << n;
    }
  }
}

TEST(LosslessBinPhasor, QuarterTurnsAreExact) {
  EXPECT_EQ(BinPhasor(0, 8).cos, 1.0);
  EXPECT_EQ(BinPhasor(0, 8).sin, 0.0);
  EXPECT_EQ(BinPhasor(2, 8).cos, 0.0);
  EXPECT_EQ(BinPhasor(2, 8).sin, 1.0);
  EXPECT_EQ(BinPhasor(4, 8).cos, -1.0);
  EXPECT_EQ(BinPhasor(6, 8).sin, -1.0);
  EXPECT_EQ(BinPhasor(1, 2).cos, -1.0);
}

std::vector<SlotState> RandomSignal(size_t n, double p_one, double p_gap, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<SlotState> s(n);
  for (auto& v : s) {
    v = u(rng) < p_gap ? SlotState::kUnobserved : (u(rng) < p_one ? SlotState::kOccupied : SlotState::kFree);
  }
  return s;
}

TEST(LosslessSlotSpectrum, EqualsADirectDftOverTheObservedSlots) {
  for (size_t n : {1u, 2u, 7u, 60u, 97u, 256u}) {
    const std::vector<SlotState> signal = RandomSignal(n, 0.4, 0.3, n);
    const SlotSpectrum spectrum = SlotSpectrum::Compute(signal);
    double ones = 0, observed = 0;
    for (SlotState s : signal) {
      observed += s != SlotState::kUnobserved;
      ones += s == SlotState::kOccupied;
    }
    ASSERT_EQ(spectrum.observed(), observed);
    const double gamma0 = observed > 0 ? ones / observed : 0;
    EXPECT_DOUBLE_EQ(spectrum.gamma0(), gamma0);
    ASSERT_EQ(spectrum.bins(), n / 2 + 1);
    std::vector<std::complex<double>> direct(n / 2 + 1);
    double largest = 1e-300;
    for (size_t k = 1; k <= n / 2; ++k) {
      std::complex<double> sum = 0;
      for (size_t i = 0; i < n; ++i) {
        if (signal[i] == SlotState::kUnobserved) continue;
        const double s = signal[i] == SlotState::kOccupied ? 1.0 : 0.0;
        sum += (s - gamma0) * std::polar(1.0, -2 * std::numbers::pi * static_cast<double>(k * i % n) / n);
      }
      direct[k] = sum / observed;
      largest = std::max(largest, std::abs(direct[k]));
    }
    for (size_t k = 1; k <= n / 2; ++k) {
      EXPECT_LE(std::abs(spectrum.gamma(k) - direct[k]), 1e-9 * largest) << "n " << n << " k " << k;
      EXPECT_NEAR(spectrum.power(k), std::norm(direct[k] * observed), 1e-9 * std::norm(largest * observed));
    }
  }
}

// A constant signal skips the transform (bin_spectrum.cc): its spectrum must still be the zeros a
// transform gives, all +0.0, with the mean and counts of the transformed path.
TEST(LosslessSlotSpectrum, ConstantSignalsWithGapsHaveAnAllZeroSpectrum) {
  for (size_t n : {1u, 2u, 7u, 60u, 97u, 256u}) {
    for (const SlotState value : {SlotState::kFree, SlotState::kOccupied}) {
      std::vector<SlotState> signal = RandomSignal(n, 0.5, 0.3, n);
      uint64_t observed = 0;
      for (SlotState& s : signal) {
        if (s != SlotState::kUnobserved) s = value, ++observed;
      }
      const SlotSpectrum spectrum = SlotSpectrum::Compute(signal);
      ASSERT_EQ(spectrum.observed(), observed) << "n " << n;
      EXPECT_EQ(spectrum.gamma0(), observed > 0 && value == SlotState::kOccupied ? 1.0 : 0.0) << "n " << n;
      for (size_t k = 1; k <= n / 2; ++k) {
        EXPECT_EQ(spectrum.power(k), 0.0) << "n " << n << " k " << k;
        EXPECT_FALSE(std::signbit(spectrum.gamma(k).real()) || std::signbit(spectrum.gamma(k).imag()))
            << "n " << n << " k " << k;
      }
      // Its model: the mean, and zero-amplitude components of phase 0 that change no prediction.
      const BinModel model = BinModel::FromSpectrum(spectrum, n - 1, 3);
      for (const BinComponent& c : model.components()) EXPECT_EQ(c.phase(), 0.0) << "n " << n;
      for (size_t i = 0; i < n; ++i) EXPECT_EQ(model.SlotValue(i), model.alpha0()) << "n " << n;
    }
  }
}

TEST(LosslessSlotSpectrum, FindsAPureToneAtItsBin) {
  const size_t n = 1200;
  std::vector<SlotState> signal(n);
  for (size_t i = 0; i < n; ++i) signal[i] = (i % 100) < 50 ? SlotState::kOccupied : SlotState::kFree;
  const SlotSpectrum spectrum = SlotSpectrum::Compute(signal);
  const BinModel model = BinModel::FromSpectrum(spectrum, n - 1, 3);
  ASSERT_EQ(model.components().size(), 3u);
  EXPECT_EQ(model.components()[0].k, 12u);   // period 100 slots
  EXPECT_EQ(model.components()[1].k, 36u);   // its third harmonic
  EXPECT_EQ(model.components()[2].k, 60u);   // and fifth
  // A square wave's fundamental has amplitude 4/π times half its height.
  EXPECT_NEAR(model.components()[0].amplitude(), 2 / std::numbers::pi, 0.01);
  EXPECT_FLOAT_EQ(model.alpha0(), 0.5f);
  EXPECT_EQ(model.order(), 3);
  EXPECT_EQ(model.length(), n);
}

TEST(LosslessBinModel, PeriodsLongerThanTwoThirdsOfTheSpanAreNotEligible) {
  const size_t n = 300;
  std::vector<SlotState> signal(n, SlotState::kUnobserved);
  // A slow wave over the whole signal, observed in slots [0, 150]: span 150 slots.
  for (size_t i = 0; i <= 150; ++i) signal[i] = i < 75 ? SlotState::kOccupied : SlotState::kFree;
  const BinModel model = BinModel::FromSpectrum(SlotSpectrum::Compute(signal), 150, 64);
  for (const BinComponent& c : model.components()) EXPECT_LE(3.0 * n, 2.0 * c.k * 150) << c.k;  // n/k ≤ 100
  EXPECT_EQ(model.components().size(), 64u);
  for (size_t j = 1; j < model.components().size(); ++j) {
    EXPECT_GE(model.components()[j - 1].amplitude(), model.components()[j].amplitude());
  }
}

TEST(LosslessBinModel, PredictorAgreesWithSlotValueToTheBit) {
  std::mt19937_64 rng(9);
  for (uint64_t n : {5ull, 97ull, 4096ull, 17280ull, 518400ull}) {
    const std::vector<SlotState> signal = RandomSignal(n, 0.5, 0.1, n);
    BinModel model = BinModel::FromSpectrum(SlotSpectrum::Compute(signal), n - 1, 6);
    const SlotPredictor predictor(model);
    for (int order = 0; order <= static_cast<int>(model.components().size()); ++order) {
      // Slots inside the signal and far after it (periodic extension).
      for (uint64_t begin : {uint64_t{0}, rng() % n, n * 3 + rng() % 1000, uint64_t{1} << 29}) {
        std::vector<double> values(300);
        predictor.Values(begin, order, values);
        for (size_t i = 0; i < values.size(); ++i) {
          ASSERT_EQ(values[i], model.SlotValue(begin + i, order)) << "n " << n << " order " << order;
        }
      }
    }
    // The continuous-time prediction is the same function of time.
    model.set_order(static_cast<int>(model.components().size()));
    for (int i = 0; i < 100; ++i) {
      const uint64_t slot = rng() % (4 * n);
      EXPECT_NEAR(model.Predict(static_cast<double>(slot)), std::clamp(model.SlotValue(slot), 0.0, 1.0), 1e-9);
    }
  }
}

TEST(LosslessBinModel, CountErrorsMatchesSlotValues) {
  const uint64_t n = 5000;
  const std::vector<SlotState> signal = RandomSignal(n, 0.3, 0.2, 1);
  const BinModel model = BinModel::FromSpectrum(SlotSpectrum::Compute(signal), n - 1, 4);
  std::vector<uint64_t> errors(7, 0);
  SlotPredictor(model).CountErrors(100, std::span<const SlotState>(signal).subspan(100), errors);
  for (int l = 0; l < 7; ++l) {
    uint64_t expected = 0;
    for (uint64_t i = 100; i < n; ++i) {
      if (signal[i] == SlotState::kUnobserved) continue;
      expected += (model.SlotValue(i, std::min(l, 4)) >= 0.5) != (signal[i] == SlotState::kOccupied);
    }
    EXPECT_EQ(errors[l], expected) << l;
  }
}

TEST(LosslessBinModel, EncodesAndRejectsCorruption) {
  const uint64_t n = 2000;
  BinModel model = BinModel::FromSpectrum(SlotSpectrum::Compute(RandomSignal(n, 0.5, 0, 2)), n - 1, 5);
  model.set_order(3);
  std::string bytes;
  model.EncodeTo(&bytes);
  EXPECT_EQ(bytes.size(), model.encoded_size());
  ByteReader reader(bytes, "test");
  EXPECT_EQ(BinModel::Decode(reader, "model"), model);
  EXPECT_TRUE(reader.Finish().ok());

  std::string empty;
  BinModel().EncodeTo(&empty);
  EXPECT_EQ(empty.size(), 1u);
  ByteReader empty_reader(empty, "test");
  EXPECT_EQ(BinModel::Decode(empty_reader, "model"), BinModel());

  // The order byte follows the varint length and the float α0.
  std::string bad_order = bytes;
  bad_order[Varint64Length(n) + 4] = 9;
  ByteReader bad(bad_order, "test");
  BinModel::Decode(bad, "model");
  EXPECT_NE(bad.status().message().find("order 9 exceeds the 5 components held"), std::string::npos) << bad.status();
}

}  // namespace
}  // namespace fremen::model
