#include "storage/model/kernels/compact_models.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "storage/model/kernels/kernel_test_data.h"
#include "storage/model/kernels/region_predict.h"

namespace fremen::model {
namespace {

constexpr int kL = 5;

// Published models of random cells at random orders, plus some unpublished ones.
struct Fixture {
  PeriodSet periods = PeriodSet::Default();
  std::vector<PublishedModel> published;
  CompactModels models{kL};

  explicit Fixture(size_t count) {
    std::mt19937_64 rng(11);
    const auto spectra = testing::RandomCellSpectra(periods, count, 5);
    models.Resize(count);
    for (size_t i = 0; i < count; ++i) {
      if (i % 7 == 3) {
        published.push_back(PublishedModel::MeanOnly(spectra[i].gamma0()));
        models.SetUnpublished(i, published.back().alpha0());
      } else {
        published.push_back(PublishedModel::FromSpectrum(spectra[i], periods, kL, static_cast<int>(rng() % (kL + 1))));
        models.Set(i, published.back());
      }
    }
  }
};

TEST(CompactModelsTest, RecordIs60BytesAtOrder5AndRoundTrips) {
  EXPECT_EQ(CompactModels::StrideFor(5), 60u);
  EXPECT_EQ(CompactModels::StrideFor(0), 8u);
  const Fixture f(200);
  for (size_t i = 0; i < f.published.size(); ++i) {
    EXPECT_EQ(f.models.Get(i), f.published[i]) << i;
    if (i % 7 == 3) {
      EXPECT_FALSE(f.models.published(i));
      EXPECT_FALSE(f.models.Holds(i, f.published[i]));
    } else {
      EXPECT_TRUE(f.models.Holds(i, f.published[i])) << i;
    }
  }
  CompactModels fresh(kL, 1);
  EXPECT_FALSE(fresh.published(0));
  EXPECT_EQ(fresh.header(0).alpha0, 0.5f);
}

// published(i) is read from a bit kept beside the records: it follows the header's flag through
// Set, SetUnpublished, MarkPublished, a shrink and a growth.
TEST(CompactModelsTest, ThePublishedBitFollowsEveryWriteOfTheRecord) {
  Fixture f(300);
  const auto agree = [&](const char* after) {
    for (size_t i = 0; i < f.models.size(); ++i) {
      ASSERT_EQ(f.models.published(i), f.models.header(i).published != 0) << "record " << i << " after " << after;
    }
  };
  agree("the fixture");
  for (size_t i = 0; i < 300; i += 3) f.models.SetUnpublished(i, 0.25f);
  agree("SetUnpublished");
  for (size_t i = 1; i < 300; i += 5) f.models.MarkPublished(i);
  agree("MarkPublished");
  f.models.Set(0, f.published[1]);
  EXPECT_TRUE(f.models.published(0));
  f.models.Resize(130);  // keeps 0..129; 128 and 129 share their word with the dropped ones
  agree("the shrink");
  f.models.Resize(400);
  agree("the growth");
  for (size_t i = 130; i < 400; ++i) EXPECT_FALSE(f.models.published(i)) << "new record " << i;
}

TEST(CompactModelsTest, PredictAllOrdersEqualsThePublishedModel) {
  const Fixture f(200);
  for (double t : {1.7e9, 1.7e9 + 12345.6, 1.7e9 + 5e5}) {
    const PhasorTable table(f.periods, t);
    for (size_t i = 0; i < f.published.size(); ++i) {
      double got[kL + 1], want[kL + 1];
      f.models.PredictAllOrders(i, table, got);
      f.published[i].PredictAllOrders(table, kL, want);
      for (int l = 0; l <= kL; ++l) EXPECT_EQ(got[l], want[l]) << i << " order " << l;
    }
  }
}

TEST(CompactModelsTest, PredictRegionEqualsPublishedModelPredictAtEveryOrder) {
  const Fixture f(1000);
  const size_t n = f.published.size();
  std::vector<float> p(n);
  std::vector<uint8_t> q(n);
  for (double t : {1.7e9, 1.7e9 + 4321.0, 1.7e9 + 9e5}) {
    const PhasorTable table(f.periods, t);
    for (int order = -1; order <= kL + 3; ++order) {  // own order, every order, and past L
      PredictRegion(f.models, table, order, p.data());
      PredictRegionU8(f.models, table, order, q.data());
      for (size_t i = 0; i < n; ++i) {
        const double want = f.published[i].Predict(table, order);
        ASSERT_NEAR(p[i], want, 1e-5) << i << " order " << order;
        ASSERT_NEAR(q[i] / 255.0, want, 0.5 / 255 + 1e-5) << i << " order " << order;
        ASSERT_GE(p[i], 0.0f);
        ASSERT_LE(p[i], 1.0f);
      }
    }
  }
}

TEST(CompactModelsTest, PredictRegionOfASubrange) {
  const Fixture f(100);
  const PhasorTable table(f.periods, 1.7e9 + 777);
  std::vector<float> all(100), part(30);
  PredictRegion(f.models, table, -1, all.data());
  PredictRegion(f.models, 40, 30, table, -1, part.data());
  for (size_t i = 0; i < part.size(); ++i) EXPECT_EQ(part[i], all[40 + i]);
}

// The listed form (what a shard's box query runs) is the same kernel: bit for bit the prediction of
// PredictRegion for each listed record, in any order and with repeats, at every order.
TEST(CompactModelsTest, PredictRecordsEqualsPredictRegionOfEachRecord) {
  const Fixture f(700);
  std::vector<uint32_t> records;
  std::mt19937_64 rng(5);
  for (size_t i = 0; i < 600; ++i) records.push_back(static_cast<uint32_t>(rng() % f.published.size()));
  const PhasorTable table(f.periods, 1.7e9 + 2468);
  std::vector<float> all(f.published.size()), listed(records.size());
  for (int order = -1; order <= kL + 1; ++order) {
    PredictRegion(f.models, table, order, all.data());
    PredictRecords(f.models, records, table, order, listed.data());
    for (size_t i = 0; i < records.size(); ++i) ASSERT_EQ(listed[i], all[records[i]]) << i << " order " << order;
  }
  PredictRecords(f.models, {}, table, -1, nullptr);  // nothing listed: nothing read or written
}

// A block of records whose highest own order is below L runs the loop of that order: every state
// still predicts exactly as at its own order, whether the block's orders are all the same (all 2 of
// L = 5) or mixed below a low maximum, and whatever the block's size.
TEST(CompactModelsTest, BlocksOfLowOrdersPredictEachStateAtItsOwnOrder) {
  const PeriodSet periods = PeriodSet::Default();
  const auto spectra = testing::RandomCellSpectra(periods, 600, 5);
  const PhasorTable table(periods, 1.7e9 + 4321);
  for (int highest = 0; highest <= kL; ++highest) {
    for (bool mixed : {false, true}) {
      CompactModels models(kL);
      models.Resize(spectra.size());
      std::vector<int> own(spectra.size());
      for (size_t i = 0; i < spectra.size(); ++i) {
        own[i] = mixed ? static_cast<int>(i % (highest + 1)) : highest;
        models.Set(i, PublishedModel::FromSpectrum(spectra[i], periods, kL, own[i]));
      }
      std::vector<float> p(spectra.size()), at_order(spectra.size());
      PredictRegion(models, table, -1, p.data());
      std::vector<uint32_t> records(spectra.size());
      for (uint32_t i = 0; i < records.size(); ++i) records[i] = i;
      std::vector<float> listed(records.size());
      PredictRecords(models, records, table, -1, listed.data());
      for (int order = 0; order <= highest; ++order) {
        PredictRegion(models, table, order, at_order.data());
        for (size_t i = 0; i < spectra.size(); ++i) {
          if (own[i] != order) continue;
          ASSERT_EQ(p[i], at_order[i]) << "record " << i << " of own order " << order << ", highest " << highest;
          ASSERT_EQ(listed[i], at_order[i]) << "record " << i << " of own order " << order;
        }
      }
    }
  }
}

TEST(CompactModelsTest, HigherMaxOrdersUseTheGenericKernel) {
  const PeriodSet periods = PeriodSet::Default();
  constexpr int kBigL = 12;
  const auto spectra = testing::RandomCellSpectra(periods, 100, 9);
  CompactModels models(kBigL, spectra.size());
  std::vector<PublishedModel> published;
  for (size_t i = 0; i < spectra.size(); ++i) {
    published.push_back(PublishedModel::FromSpectrum(spectra[i], periods, kBigL, static_cast<int>(i % (kBigL + 1))));
    models.Set(i, published.back());
  }
  const PhasorTable table(periods, 1.7e9 + 31337);
  std::vector<float> p(spectra.size());
  for (int order : {-1, 3, 9, 12}) {
    PredictRegion(models, table, order, p.data());
    for (size_t i = 0; i < spectra.size(); ++i) EXPECT_NEAR(p[i], published[i].Predict(table, order), 1e-5);
  }
}

}  // namespace
}  // namespace fremen::model
