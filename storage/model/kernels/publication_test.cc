#include "storage/model/kernels/publication.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "storage/model/kernels/kernel_test_data.h"

namespace fremen::model {
namespace {

struct Case {
  int periods;
  int max_order;
};

class PublicationTest : public ::testing::TestWithParam<Case> {};

// PublishAll must reproduce FromSpectrum with BestOrder's order exactly, through both error forms.
TEST_P(PublicationTest, EqualsFromSpectrumWithTheBestOrder) {
  const Case c = GetParam();
  const PeriodSet periods = *PeriodSet::Harmonics(kWeekSeconds, c.periods);
  auto spectra = testing::RandomCellSpectra(periods, 2000, 21);
  // Degenerate cells: all-zero spectrum, one observation, constant values (every γ_k exactly tied).
  spectra[0] = CompactSpectrum(periods.size());
  spectra[1].AddBatch(std::vector<Observation>{{1.7e9, 1.0f}}, periods);
  spectra[2] = CompactSpectrum(periods.size());
  spectra[2].AddBatch(std::vector<Observation>{{1.7e9, 1.0f}, {1.7e9 + 2e6, 1.0f}}, periods);

  std::mt19937_64 rng(22);
  RecordArena arena(periods.size(), spectra.size());
  OrderErrorTable table(c.max_order, spectra.size());
  std::vector<OrderErrors> errors;
  for (size_t i = 0; i < spectra.size(); ++i) {
    arena.Store(i, spectra[i]);
    errors.push_back(testing::RandomOrderErrors(c.max_order, rng));
    table.Set(i, errors.back());
  }
  CompactModels from_table(c.max_order, spectra.size()), from_objects(c.max_order, spectra.size());
  // The paper's rule: RandomOrderErrors is made so that its minima cover every order.
  const OrderRule rule{OrderSelection::kPaper};
  PublishAll(arena, table, periods, from_table, rule);
  PublishAll(arena, errors, periods, from_objects, rule);

  std::vector<int> orders_seen(c.max_order + 1);
  for (size_t i = 0; i < spectra.size(); ++i) {
    const int order = errors[i].BestOrder(rule);
    ++orders_seen[order];
    const PublishedModel want = PublishedModel::FromSpectrum(spectra[i], periods, c.max_order, order);
    ASSERT_TRUE(from_table.Holds(i, want)) << "cell " << i;
    ASSERT_TRUE(from_objects.Holds(i, want)) << "cell " << i;
  }
  for (int l = 0; l <= c.max_order; ++l) EXPECT_GT(orders_seen[l], 0) << "order " << l;
}

INSTANTIATE_TEST_SUITE_P(Shapes, PublicationTest,
                         ::testing::Values(Case{24, 5}, Case{24, 0}, Case{24, 1}, Case{24, 24}, Case{168, 8},
                                           Case{7, 5}));

TEST(PublisherTest, PublishesAGivenOrderIntoAnyRecord) {
  const PeriodSet periods = PeriodSet::Default();
  const auto spectra = testing::RandomCellSpectra(periods, 10, 23);
  const Publisher publisher(periods, 5);
  CompactModels models(5, 1);
  for (size_t i = 0; i < 10; ++i) {
    publisher.Publish(spectra[i], 4, models, 0);
    EXPECT_TRUE(models.Holds(0, PublishedModel::FromSpectrum(spectra[i], periods, 5, 4)));
  }
}

}  // namespace
}  // namespace fremen::model
