#include "storage/model/kernels/wide_bodies.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "storage/model/periods.h"
#include "storage/model/phasor.h"
#include "storage/model/kernels/record_arena.h"

namespace fremen::model {
namespace {

// The largest difference between a float record's body and a double reference body.
double BodyError(const float* body, const BasicSpectrum<double>& reference) {
  double worst = 0;
  for (size_t i = 0; i < reference.periods() * kRealsPerPeriod; ++i) {
    worst = std::max(worst, std::fabs(double{body[i]} - reference.body()[i]));
  }
  return worst;
}

TEST(WideBodiesTest, WidenedRecordKeepsItsAccuracyWhereFloatLosesIt) {
  // 2^22 observations of one state: the first 2^20 in float, the rest in double through WideBodies,
  // beside a record that stays float and a double reference.
  const PeriodSet periods = *PeriodSet::FromPeriods({86400, 3600});
  constexpr size_t kTimes = 997;
  std::vector<ScanPhasors<float>> narrow_phasors;
  std::vector<ScanPhasors<double>> wide_phasors;
  std::vector<PhasorTable> tables;
  for (size_t i = 0; i < kTimes; ++i) {
    tables.emplace_back(periods, 1.7e9 + 61.3 * i);
    narrow_phasors.emplace_back(tables.back());
    wide_phasors.emplace_back(tables.back());
  }
  RecordArena arena(periods.size(), 2);  // record 0 is widened, record 1 stays float
  WideBodies wide(periods.size());
  BasicSpectrum<double> reference(periods.size());
  constexpr size_t kObservations = size_t{1} << 22;
  for (size_t i = 0; i < kObservations; ++i) {
    const float s = (i % 7 < 3) ? 1.0f : 0.0f;
    const size_t t = i % kTimes;
    if (i == kCompactRecordLimit) wide.Widen(0, arena.body(0));
    if (wide.wide(0)) {
      wide.Fold(0, arena.header(0), arena.body(0), tables[t], s);
    } else {
      FoldObservation(arena.header(0), arena.body(0), narrow_phasors[t], s);
    }
    FoldObservation(arena.header(1), arena.body(1), narrow_phasors[t], s);
    reference.Observe(wide_phasors[t], s);
  }
  EXPECT_EQ(arena.header(0).n, kObservations);
  EXPECT_EQ(arena.header(0), arena.header(1));
  const double widened_error = BodyError(arena.body(0), reference);
  const double float_error = BodyError(arena.body(1), reference);
  EXPECT_LT(widened_error, 2e-6);
  EXPECT_GT(float_error, 20 * widened_error) << "the float record should have lost accuracy by now";
}

TEST(WideBodiesTest, WidenStartsFromTheFloatBodyAndOnlyMarksThatRecord) {
  const PeriodSet periods = PeriodSet::Default();
  RecordArena arena(periods.size(), 5);
  for (size_t i = 0; i < periods.size() * kRealsPerPeriod; ++i) arena.body(3)[i] = 0.25f * static_cast<float>(i % 4);
  WideBodies wide(periods.size());
  EXPECT_FALSE(wide.wide(3));
  EXPECT_EQ(wide.size(), 0u);
  wide.Widen(3, arena.body(3));
  EXPECT_TRUE(wide.wide(3));
  EXPECT_FALSE(wide.wide(0));
  EXPECT_FALSE(wide.wide(4));
  EXPECT_EQ(wide.size(), 1u);
  wide.Widen(3, arena.body(3));  // again: still one wide record
  EXPECT_EQ(wide.size(), 1u);
  EXPECT_GE(wide.bytes(), periods.size() * kRealsPerPeriod * sizeof(double));

  // A fold of a wide record starting from that body is the fold of the same float body in double.
  const PhasorTable table(periods, 1.7e9);
  const ScanPhasors<double> phasors(table);
  BasicSpectrum<double> expected(periods.size());
  for (size_t i = 0; i < periods.size() * kRealsPerPeriod; ++i) expected.body()[i] = arena.body(3)[i];
  expected.mutable_header() = arena.header(3);
  wide.Fold(3, arena.header(3), arena.body(3), table, 1.0f);
  expected.Observe(phasors, 1.0f);
  EXPECT_EQ(arena.header(3), expected.header());
  for (size_t i = 0; i < periods.size() * kRealsPerPeriod; ++i) {
    EXPECT_EQ(arena.body(3)[i], static_cast<float>(expected.body()[i])) << i;
  }
}

TEST(WideBodiesTest, FoldIsFoldObservationWithTheTablesPhasorsBitForBit) {
  // Fold reads the table's cos and sin instead of ScanPhasors<double>; a record's bits must not
  // depend on which one folded it (recovery and a recomputation compare them exactly).
  const PeriodSet periods = PeriodSet::Default();
  const size_t reals = periods.size() * kRealsPerPeriod;
  RecordArena arena(periods.size(), 1);
  WideBodies wide(periods.size());
  wide.Widen(0, arena.body(0));
  BasicSpectrum<double> expected(periods.size());
  const float values[] = {1.0f, 0.0f, 0.3f, 1.0f, 0.75f};
  for (size_t i = 0; i < 5000; ++i) {
    const PhasorTable table(periods, 1.7e9 + 37.1 * static_cast<double>(i) * static_cast<double>(i % 13));
    const float s = values[i % 5];
    wide.Fold(0, arena.header(0), arena.body(0), table, s);
    expected.Observe(ScanPhasors<double>(table), s);
  }
  EXPECT_EQ(arena.header(0), expected.header());
  const std::string encoded = wide.Encode(0);
  ASSERT_EQ(encoded.size(), 1 + reals * sizeof(double));
  for (size_t i = 0; i < reals; ++i) {
    double folded;
    std::memcpy(&folded, encoded.data() + 1 + i * sizeof(double), sizeof(double));  // little-endian host
    EXPECT_EQ(std::bit_cast<uint64_t>(folded), std::bit_cast<uint64_t>(expected.body()[i])) << i;
  }
}

}  // namespace
}  // namespace fremen::model
