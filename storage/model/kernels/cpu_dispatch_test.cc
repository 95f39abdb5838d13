#include "storage/model/kernels/cpu_dispatch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "storage/model/kernels/region_predict.h"
#include "storage/model/kernels/scan_update.h"

// The kernels cloned for AVX2 (cpu_dispatch.h) give bit for bit what a plain scalar loop gives, on
// whichever path the loader chose on this machine (named in each test's output and XML property):
// "avx2" on the development machines, "default" (the build's own target) on an older CPU, "none"
// in a build without clones. The references below are one element at a time, unvectorised.

// GCC: keep the references scalar, so that they are the plain IEEE operations in source order.
#if defined(__GNUC__) && !defined(__clang__)
#define FREMEN_SCALAR_REFERENCE __attribute__((optimize("no-tree-vectorize")))
#else
#define FREMEN_SCALAR_REFERENCE
#endif

namespace fremen::model {
namespace {

constexpr int kL = 5;

// With FMA in the build's own target (FREMEN_MARCH=native on most machines), the compiler may fuse
// a·b + c in one loop and not in another: equality to a plain loop is then not a property of the
// code. The portable build (and each of its clones) has no FMA.
bool BuildMayFuseMultiplyAdd() {
#ifdef __FMA__
  return true;
#else
  return false;
#endif
}

void NameThePath() {
  ::testing::Test::RecordProperty("kernel_dispatch", KernelDispatchPath());
  std::printf("kernel dispatch path: %s\n", KernelDispatchPath());
}

FREMEN_SCALAR_REFERENCE float PlainPrediction(const CompactModels& models, size_t i, const PhasorTable& phasors,
                                              int order) {
  const int used = order < 0 ? models.header(i).order : std::min(order, models.max_order());
  float p = models.header(i).alpha0;
  for (int j = 0; j < used; ++j) {
    const uint16_t k = models.k(i)[j];
    p += models.a(i)[j] * phasors.cos_f()[k] - models.b(i)[j] * phasors.sin_f()[k];
  }
  return std::min(std::max(p, 0.0f), 1.0f);
}

FREMEN_SCALAR_REFERENCE void PlainFold(SpectrumHeader& h, float* body, const ScanPhasors<float>& phasors, float s) {
  const double t = phasors.time();
  if (h.n == 0) {
    h.t_first = h.t_last = t;
  } else {
    h.t_first = std::min(h.t_first, t);
    h.t_last = std::max(h.t_last, t);
  }
  h.sum_s += s;
  h.n += 1;
  const float d = static_cast<float>(1.0 / h.n);
  for (size_t i = 0; i < phasors.periods() * kRealsPerPeriod; ++i) {
    const float target = s * phasors.qs()[i] + phasors.qe()[i];
    body[i] += d * (target - body[i]);
  }
}

// Models with every order 0..L, k anywhere in Ω and components up to ±0.5, so that predictions leave
// [0, 1] on both sides and the clamp matters.
CompactModels RandomModels(size_t count, size_t periods, uint64_t seed) {
  CompactModels models(kL, count);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < count; ++i) {
    models.header(i) = {u(rng), static_cast<uint8_t>(rng() % (kL + 1)), 1, kL};
    for (int j = 0; j < kL; ++j) {
      models.k(i)[j] = static_cast<uint16_t>(rng() % periods);
      models.a(i)[j] = u(rng) - 0.5f;
      models.b(i)[j] = u(rng) - 0.5f;
    }
  }
  return models;
}

TEST(KernelDispatchTest, RegionPredictionEqualsAPlainLoopBitForBit) {
  NameThePath();
  if (BuildMayFuseMultiplyAdd()) GTEST_SKIP() << "a build with FMA (FREMEN_MARCH=native): no clones to compare";
  const PeriodSet periods = PeriodSet::Default();
  // Not a multiple of any vector width or of the kernel's 256-cell blocks, from an odd first record.
  constexpr size_t kCount = 1000 + 3, kFirst = 1;
  const CompactModels models = RandomModels(kFirst + kCount, periods.size(), 21);
  std::vector<uint32_t> records(777);
  std::mt19937_64 rng(22);
  for (uint32_t& r : records) r = static_cast<uint32_t>(rng() % models.size());
  std::vector<float> p(kCount), listed(records.size());
  std::vector<uint8_t> q(kCount);
  for (double t : {1.7e9, 1.7e9 + 4321.5, 1.7e9 + 9e5}) {
    const PhasorTable phasors(periods, t);
    for (int order = -1; order <= kL + 1; ++order) {  // each record's own, every order, past L
      PredictRegion(models, kFirst, kCount, phasors, order, p.data());
      PredictRegionU8(models, kFirst, kCount, phasors, order, q.data());
      PredictRecords(models, records, phasors, order, listed.data());
      for (size_t i = 0; i < kCount; ++i) {
        const float want = PlainPrediction(models, kFirst + i, phasors, order);
        ASSERT_EQ(std::memcmp(&p[i], &want, sizeof want), 0) << "record " << kFirst + i << " order " << order;
        ASSERT_EQ(q[i], QuantizeProbability(want)) << "record " << kFirst + i << " order " << order;
      }
      for (size_t i = 0; i < records.size(); ++i) {
        const float want = PlainPrediction(models, records[i], phasors, order);
        ASSERT_EQ(std::memcmp(&listed[i], &want, sizeof want), 0) << "listed " << i << " order " << order;
      }
    }
  }
}

void ExpectSameRecords(const RecordArena& arena, const RecordArena& reference) {
  for (size_t i = 0; i < arena.size(); ++i) {
    ASSERT_EQ(arena.header(i), reference.header(i)) << "cell " << i;
    ASSERT_EQ(std::memcmp(arena.body(i), reference.body(i), arena.periods() * kRealsPerPeriod * sizeof(float)), 0)
        << "cell " << i;
  }
}

// Both update kernels, at the default Ω (K = 24: the fully unrolled fold) and another K (the generic
// loop), over many scans so that the running means are far from their first values.
TEST(KernelDispatchTest, ScanUpdatesEqualAPlainLoopBitForBit) {
  NameThePath();
  if (BuildMayFuseMultiplyAdd()) GTEST_SKIP() << "a build with FMA (FREMEN_MARCH=native): no clones to compare";
  for (const PeriodSet& periods : {PeriodSet::Default(), *PeriodSet::Harmonics(86400.0 * 30, 7)}) {
    constexpr size_t kCells = 300;
    RecordArena dense(periods.size(), kCells), listed(periods.size(), kCells), reference(periods.size(), kCells),
        listed_reference(periods.size(), kCells);
    std::mt19937_64 rng(23);
    for (int scan = 0; scan < 50; ++scan) {
      const ScanPhasors<float> phasors(PhasorTable(periods, 1.7e9 + 1013.25 * scan));
      const size_t first = rng() % kCells;
      std::vector<float> values(rng() % (kCells - first + 1));
      for (float& v : values) v = static_cast<float>(rng() % 5) / 4;
      ApplyDenseScan(dense, phasors, first, values);
      for (size_t i = 0; i < values.size(); ++i) {
        PlainFold(reference.header(first + i), reference.body(first + i), phasors, values[i]);
      }
      std::vector<uint32_t> cells(values.size());
      for (uint32_t& c : cells) c = static_cast<uint32_t>(rng() % kCells);  // any order, repeats
      ApplyScan(listed, phasors, cells, values);
      for (size_t i = 0; i < cells.size(); ++i) {
        PlainFold(listed_reference.header(cells[i]), listed_reference.body(cells[i]), phasors, values[i]);
      }
    }
    ExpectSameRecords(dense, reference);
    ExpectSameRecords(listed, listed_reference);
  }
}

}  // namespace
}  // namespace fremen::model
