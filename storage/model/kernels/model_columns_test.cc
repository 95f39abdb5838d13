// ModelColumns and PredictColumns: the columns hold each published model at its own order, and a
// run of them predicts bit for bit what the records give at each state's own order (PredictRecords
// at order -1), as floats and as bytes, on every path this machine can take: AVX-512 (Ω of up to
// 16 and 32 periods: one or two vectors of the table), AVX2 (up to 8, 16, 24 and 32: one to four)
// and scalar (any Ω), for runs whose lengths are not multiples of the vectors', which start
// anywhere and end anywhere, including at the columns' end.
#include "storage/model/kernels/model_columns.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "storage/model/kernels/kernel_test_data.h"
#include "storage/model/kernels/region_predict.h"

namespace fremen::model {
namespace {

constexpr int kL = 5;

// Published models of random cells at every order 0..L (some with more components than their
// order), appended to the columns in a shuffled order.
struct Fixture {
  PeriodSet periods;
  CompactModels models{kL};
  std::vector<uint32_t> records;  // records[i]: the record behind column model i
  ModelColumns columns{kL};

  explicit Fixture(size_t count, PeriodSet omega = PeriodSet::Default()) : periods(std::move(omega)) {
    std::mt19937_64 rng(5);
    const auto spectra = testing::RandomCellSpectra(periods, count, 9);
    models.Resize(count);
    for (size_t i = 0; i < count; ++i) {
      const PublishedModel full = PublishedModel::FromSpectrum(spectra[i], periods, kL, kL);
      // Its components, at a lower selected order for some.
      const int order = static_cast<int>(rng() % (kL + 1));
      models.Set(i, PublishedModel::Restore(full.alpha0(), order, full.components()));
      records.push_back(static_cast<uint32_t>(i));
    }
    std::shuffle(records.begin(), records.end(), rng);
    columns.Resize(count);
    for (size_t i = 0; i < count; ++i) columns.SetZero(i, models, records[i]);
  }
};

TEST(ModelColumnsTest, HoldEachModelAtItsOwnOrder) {
  const Fixture f(300);
  ASSERT_EQ(f.columns.size(), 300u);
  ASSERT_EQ(f.columns.max_order(), kL);
  size_t below_count = 0;
  for (size_t i = 0; i < f.columns.size(); ++i) {
    const uint32_t r = f.records[i];
    const CompactModelHeader& h = f.models.header(r);
    EXPECT_EQ(f.columns.alpha0()[i], h.alpha0);
    EXPECT_EQ(f.columns.order()[i], h.order);
    below_count += h.order < h.count;
    for (int j = 0; j < kL; ++j) {
      const bool used = j < h.order;
      EXPECT_EQ(f.columns.k(j)[i], used ? f.models.k(r)[j] : 0) << i << " " << j;
      EXPECT_EQ(f.columns.a(j)[i], used ? f.models.a(r)[j] : 0.0f) << i << " " << j;
      EXPECT_EQ(f.columns.b(j)[i], used ? f.models.b(r)[j] : 0.0f) << i << " " << j;
    }
  }
  EXPECT_GT(below_count, 0u);  // some components past the own order were left out
  EXPECT_GT(f.columns.memory_bytes(), f.columns.size() * (sizeof(float) + kL * 10));
}

// A shrink leaves no model behind: the columns grow again with zero models, and the entries a vector
// kernel reads past the end are zeros.
TEST(ModelColumnsTest, ShrinkThenGrowGivesZeroModels) {
  Fixture f(40);
  f.columns.Resize(10);
  f.columns.Resize(30);
  ASSERT_EQ(f.columns.size(), 30u);
  for (size_t i = 10; i < 30 + ModelColumns::kReadablePast; ++i) {
    if (i < 30) {
      EXPECT_EQ(f.columns.order()[i], 0) << i;
    }
    EXPECT_EQ(f.columns.alpha0()[i], 0.0f) << i;
    for (int j = 0; j < kL; ++j) {
      EXPECT_EQ(f.columns.k(j)[i], 0) << i << " " << j;
      EXPECT_EQ(f.columns.a(j)[i], 0.0f) << i << " " << j;
      EXPECT_EQ(f.columns.b(j)[i], 0.0f) << i << " " << j;
    }
  }
  EXPECT_EQ(f.columns.alpha0()[9], f.models.header(f.records[9]).alpha0);  // the kept ones are kept
}

const char* PathName(ColumnsPath path) {
  switch (path) {
    case ColumnsPath::kAvx512: return "avx512";
    case ColumnsPath::kAvx2: return "avx2";
    case ColumnsPath::kScalar: return "scalar";
  }
  return "?";
}

// Runs of every length up to 40 at several starts, runs that end at the columns' last model, then one
// longer than a block (256), at the highest own order of the run and at L: each value equals the
// records' own-order prediction. For Ω of several sizes, on each path the machine can take, and
// through PredictColumns (the fastest of them).
class PredictColumnsTest : public ::testing::TestWithParam<int> {};

TEST_P(PredictColumnsTest, EqualsPredictRecordsAtOwnOrdersOnEveryPath) {
  const int period_count = GetParam();
  const Fixture f(700, *PeriodSet::Harmonics(kWeekSeconds, period_count));
  ASSERT_TRUE(PredictColumnsCan(ColumnsPath::kScalar, f.periods.size()));
  if (period_count > 32) {
    EXPECT_EQ(PredictColumnsPath(f.periods.size()), ColumnsPath::kScalar);
  }
  std::string paths;
  for (const ColumnsPath path : {ColumnsPath::kAvx512, ColumnsPath::kAvx2, ColumnsPath::kScalar}) {
    if (PredictColumnsCan(path, f.periods.size())) paths += std::string(paths.empty() ? "" : ",") + PathName(path);
  }
  ::testing::Test::RecordProperty("paths", paths);
  ::testing::Test::RecordProperty("chosen", PathName(PredictColumnsPath(f.periods.size())));
  for (const double t : {1.7e9, 1.7e9 + 12345.6, 1.7e9 + 86400.0 * 9.3}) {
    const PhasorTable table(f.periods, t);
    std::vector<float> expected(f.records.size());
    PredictRecords(f.models, f.records, table, -1, expected.data());
    const auto check = [&](size_t first, size_t count) {
      int highest = 0;
      for (size_t i = first; i < first + count; ++i) highest = std::max<int>(highest, f.columns.order()[i]);
      for (const int terms : {highest, kL}) {
        const auto compare = [&](const char* path, const std::vector<float>& p, const std::vector<uint8_t>& q) {
          for (size_t i = 0; i < count; ++i) {
            // Bit for bit: the same IEEE operations in the same order.
            ASSERT_EQ(std::memcmp(&p[i], &expected[first + i], sizeof(float)), 0)
                << path << " t " << t << " run " << first << "+" << count << " terms " << terms << " model " << i;
            ASSERT_EQ(q[i], QuantizeProbability(expected[first + i])) << path << " " << i;
          }
          EXPECT_EQ(p[count], 7.0f) << path;  // nothing written past the run
          EXPECT_EQ(q[count], 77) << path;
        };
        std::vector<float> p(count + 1, 7.0f);
        std::vector<uint8_t> q(count + 1, 77);
        PredictColumns(f.columns, first, count, terms, table, p.data());
        PredictColumnsU8(f.columns, first, count, terms, table, q.data());
        compare("chosen", p, q);
        for (const ColumnsPath path : {ColumnsPath::kAvx512, ColumnsPath::kAvx2, ColumnsPath::kScalar}) {
          if (!PredictColumnsCan(path, f.periods.size())) continue;
          std::fill(p.begin(), p.end(), 7.0f);
          std::fill(q.begin(), q.end(), 77);
          PredictColumnsOn(path, f.columns, first, count, terms, table, p.data());
          PredictColumnsOn(path, f.columns, first, count, terms, table, q.data());
          compare(PathName(path), p, q);
        }
      }
    };
    for (size_t count = 0; count <= 40; ++count) {
      for (const size_t first : {size_t{0}, size_t{3}, size_t{101}, f.columns.size() - count}) check(first, count);
    }
    check(13, 600);
  }
}

INSTANTIATE_TEST_SUITE_P(PeriodCounts, PredictColumnsTest, ::testing::Values(5, 8, 12, 16, 24, 32, 33, 40),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return "Omega" + std::to_string(info.param);
                         });

}  // namespace
}  // namespace fremen::model
