#include "storage/brick_models.h"

#include <gtest/gtest.h>

#include <vector>

namespace fremen::storage {
namespace {

using model::CompactModels;
using model::PublishedModel;

// A model told apart by its number: alpha0 and the components' fields all derive from it. Order 1
// of 2 components for odd numbers, 2 for even ones.
PublishedModel ModelNumber(uint32_t n) {
  return PublishedModel::Restore(0.01f * static_cast<float>(n % 90), n % 2 == 1 ? 1 : 2,
                                 {{static_cast<uint16_t>(n % 7), 0.001f * n, -0.002f * n},
                                  {static_cast<uint16_t>(n % 11 + 1), 0.003f * n, 0.004f * n}});
}

// Column model i holds ModelNumber(n) at its own order: the second component only when it is used.
void ExpectColumnHolds(const model::ModelColumns& columns, size_t i, uint32_t n) {
  const PublishedModel m = ModelNumber(n);
  EXPECT_EQ(columns.alpha0()[i], m.alpha0()) << n;
  EXPECT_EQ(columns.order()[i], m.order()) << n;
  for (int j = 0; j < columns.max_order(); ++j) {
    const bool used = j < m.order();
    EXPECT_EQ(columns.k(j)[i], used ? m.components()[j].k : 0) << n << " " << j;
    EXPECT_EQ(columns.a(j)[i], used ? m.components()[j].a : 0.0f) << n << " " << j;
    EXPECT_EQ(columns.b(j)[i], used ? m.components()[j].b : 0.0f) << n << " " << j;
  }
}

// Three bricks: one with dynamic cells with and without published models, one with none, one
// with only unpublished ones but one. Each brick's published models must be copied in its image's
// order, in one run, with their cells and the run's highest own order; its unpublished cells
// listed; and every dynamic cell covered.
TEST(BrickModelsTest, CopiesEachBricksPublishedModelsInOneRun) {
  CompactModels models(/*max_order=*/3, /*size=*/10);
  for (uint32_t d : {1u, 2u, 5u, 7u, 9u}) models.Set(d, ModelNumber(d));
  models.SetUnpublished(3, 0.25f);
  std::vector<BrickImage> images(3);
  // Brick 0: states 5, 3 (unpublished), 1, 2 at cells 17, 4, 300, 511.
  images[0].Set(17, 5);
  images[0].Set(4, 3);
  images[0].Set(300, 1);
  images[0].Set(511, 2);
  // Brick 1: never changed and unobserved cells only.
  images[1].Set(0, BrickImage::kNeverChanged | 1);
  // Brick 2: states 0 and 4 (never published) at cells 8 and 9, then 7 at cell 2.
  images[2].Set(8, 0);
  images[2].Set(9, 4);
  images[2].Set(2, 7);

  const BrickModels copy(images, models, /*generation=*/42);
  EXPECT_EQ(copy.generation(), 42u);
  ASSERT_EQ(copy.size(), 3u);
  ASSERT_EQ(copy.models().size(), 4u);
  EXPECT_EQ(copy.models().max_order(), 3);

  const BrickModels::Brick& b0 = copy.brick(0);
  EXPECT_EQ(b0.first, 0u);
  ASSERT_EQ(b0.count, 3u);
  EXPECT_EQ(b0.covered, 4u);
  EXPECT_EQ(b0.terms, 2);  // state 2's order
  const uint32_t states[] = {5, 1, 2}, cells[] = {17, 300, 511};
  for (uint32_t i = 0; i < 3; ++i) {
    ExpectColumnHolds(copy.models(), b0.first + i, states[i]);
    EXPECT_EQ(copy.cell(b0.first + i), cells[i]) << i;
  }
  ASSERT_EQ(b0.others_count, 1u);
  EXPECT_EQ(copy.others()[b0.others_first].handle, 3u);
  EXPECT_EQ(copy.others()[b0.others_first].cell, 4u);

  const BrickModels::Brick& b1 = copy.brick(1);
  EXPECT_EQ(b1.count, 0u);
  EXPECT_EQ(b1.covered, 0u);
  EXPECT_EQ(b1.others_count, 0u);
  EXPECT_EQ(b1.terms, 0);

  const BrickModels::Brick& b2 = copy.brick(2);
  EXPECT_EQ(b2.first, 3u);
  ASSERT_EQ(b2.count, 1u);
  ExpectColumnHolds(copy.models(), 3, 7);
  EXPECT_EQ(copy.cell(3), 2u);
  EXPECT_EQ(b2.covered, 3u);
  EXPECT_EQ(b2.terms, 1);  // state 7's order
  ASSERT_EQ(b2.others_count, 2u);
  EXPECT_EQ(copy.others()[b2.others_first].handle, 0u);
  EXPECT_EQ(copy.others()[b2.others_first + 1].handle, 4u);
  EXPECT_EQ(copy.others()[b2.others_first + 1].cell, 9u);
  EXPECT_GT(copy.memory_bytes(), copy.models().size() * sizeof(float));
}

}  // namespace
}  // namespace fremen::storage
