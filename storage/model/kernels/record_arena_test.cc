#include "storage/model/kernels/record_arena.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "storage/model/kernels/kernel_test_data.h"

namespace fremen::model {
namespace {

bool RecordEquals(const RecordArena& arena, size_t i, const CompactSpectrum& spectrum) {
  return arena.header(i) == spectrum.header() &&
         std::memcmp(arena.body(i), spectrum.body(), spectrum.periods() * kRealsPerPeriod * sizeof(float)) == 0;
}

TEST(RecordArenaTest, StrideIsWholeCacheLinesAndWithinTheMemoryTarget) {
  EXPECT_EQ(RecordArena::StrideFor(24), 448u);  // 16·K + 64 at the default Ω
  for (size_t k = 1; k <= 200; ++k) {
    const size_t stride = RecordArena::StrideFor(k);
    EXPECT_EQ(stride % 64, 0u);
    EXPECT_GE(stride, CompactSpectrum::RecordBytes(k));
    EXPECT_LT(stride, CompactSpectrum::RecordBytes(k) + 64);
  }
}

TEST(RecordArenaTest, NewRecordsAreEmptySpectraWithAlignedBodies) {
  const PeriodSet periods = PeriodSet::Default();
  RecordArena arena(periods.size(), 10);
  const CompactSpectrum empty(periods.size());
  for (size_t i = 0; i < arena.size(); ++i) {
    EXPECT_TRUE(RecordEquals(arena, i, empty));
    EXPECT_EQ(reinterpret_cast<uintptr_t>(arena.body(i)) % 64, 0u);
  }
  EXPECT_EQ(arena.Append(), 10u);
  EXPECT_TRUE(RecordEquals(arena, 10, empty));
}

TEST(RecordArenaTest, StoreLoadAndGrowthKeepRecords) {
  const PeriodSet periods = PeriodSet::Default();
  const auto spectra = testing::RandomCellSpectra(periods, 50, 1);
  RecordArena arena(periods.size());
  for (const CompactSpectrum& s : spectra) arena.Store(arena.Append(), s);
  // Past 32 MiB the buffer switches to huge-page alignment: growth must still copy everything.
  arena.Resize(100000);
  for (size_t i = 0; i < spectra.size(); ++i) {
    EXPECT_TRUE(RecordEquals(arena, i, spectra[i]));
    CompactSpectrum loaded(periods.size());
    arena.Load(i, loaded);
    EXPECT_EQ(loaded, spectra[i]);
  }
  EXPECT_TRUE(RecordEquals(arena, 99999, CompactSpectrum(periods.size())));
  RecordArena moved = std::move(arena);
  EXPECT_TRUE(RecordEquals(moved, 7, spectra[7]));
  moved.Resize(3);
  EXPECT_EQ(moved.size(), 3u);
  EXPECT_TRUE(RecordEquals(moved, 2, spectra[2]));
}

}  // namespace
}  // namespace fremen::model
