#include "client/lib/scan_builder.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace fremen::client {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(ScanBuilderTest, CellsBecomeParallelArrays) {
  ScanBuilder builder(1.7e9);
  builder.AddCell({1, 2, 0}, 1).AddCell({3, 4, 5}, 0.25f);
  EXPECT_EQ(builder.size(), 2u);
  auto scan = builder.Build();
  ASSERT_TRUE(scan.ok()) << scan.status();
  EXPECT_EQ(scan->observations, 2u);
  EXPECT_DOUBLE_EQ(scan->request.time(), 1.7e9);
  const v1::CellObservations& cells = scan->request.cells();
  EXPECT_THAT(cells.cells().x(), ElementsAre(1, 3));
  EXPECT_THAT(cells.cells().y(), ElementsAre(2, 4));
  EXPECT_THAT(cells.cells().z(), ElementsAre(0, 5));
  EXPECT_THAT(cells.values(), ElementsAre(1.0f, 0.25f));
}

TEST(ScanBuilderTest, WithTheGridABinaryCellScanGoesCompactSortedByIndex) {
  ScanBuilder builder(1.7e9);
  builder.SetGrid({10, 10, 2});
  for (uint32_t x = 9; x > 0; --x) builder.AddCell({x, 3, 1}, x % 2 ? 1.0f : 0.0f);
  auto scan = builder.Build();
  ASSERT_TRUE(scan.ok()) << scan.status();
  ASSERT_TRUE(scan->request.has_compact());
  EXPECT_EQ(scan->observations, 9u);
  // Index 131 (x 1, y 3, z 1) first, then gaps of 1; x odd = 1: bits 1, 0, 1, ... from x = 1.
  EXPECT_EQ(scan->request.compact().indices(), std::string("\x83\x01") + std::string(8, '\x01'));
  EXPECT_EQ(scan->request.compact().occupied(), std::string("\x55\x01", 2));
  // The grid stays for the next scan.
  builder.AddCell({0, 0, 0}, 1).AddCell({1, 0, 0}, 0);
  EXPECT_TRUE(builder.Build()->request.has_compact());
}

TEST(ScanBuilderTest, SoftValuesCellsOutsideTheGridOrTwiceStayCellObservations) {
  ScanBuilder builder(1.7e9);
  builder.SetGrid({10, 10, 1});
  EXPECT_TRUE(builder.AddCell({1, 1, 0}, 0.5f).AddCell({2, 1, 0}, 1).Build()->request.has_cells());
  EXPECT_TRUE(builder.AddCell({10, 1, 0}, 1).AddCell({2, 1, 0}, 1).Build()->request.has_cells());
  EXPECT_TRUE(builder.AddCell({2, 1, 0}, 1).AddCell({2, 1, 0}, 0).Build()->request.has_cells());
  ScanBuilder no_grid(1.7e9);
  EXPECT_TRUE(no_grid.AddCell({1, 1, 0}, 1).AddCell({2, 1, 0}, 1).Build()->request.has_cells());
}

TEST(ScanBuilderTest, PointsBecomeParallelArrays) {
  ScanBuilder builder(10);
  builder.AddPoint({0.5, 1.5, 0}, 1);
  auto scan = builder.Build();
  ASSERT_TRUE(scan.ok()) << scan.status();
  EXPECT_THAT(scan->request.points().points().x(), ElementsAre(0.5));
  EXPECT_THAT(scan->request.points().points().y(), ElementsAre(1.5));
  EXPECT_THAT(scan->request.points().values(), ElementsAre(1.0f));
}

TEST(ScanBuilderTest, StatesCarryNamesAndGroupsOnlyWhenSomeAreSet) {
  ScanBuilder plain(10);
  plain.AddState(7, 1).AddState(8, 0);
  auto unlabelled = plain.Build();
  ASSERT_TRUE(unlabelled.ok());
  EXPECT_THAT(unlabelled->request.states().ids(), ElementsAre(7u, 8u));
  EXPECT_EQ(unlabelled->request.states().names_size(), 0);
  EXPECT_EQ(unlabelled->request.states().groups_size(), 0);

  ScanBuilder labelled(10);
  labelled.AddState(7, 1, "door-a", "doors").AddState(8, 0);
  auto scan = labelled.Build();
  ASSERT_TRUE(scan.ok());
  EXPECT_THAT(scan->request.states().names(), ElementsAre("door-a", ""));
  EXPECT_THAT(scan->request.states().groups(), ElementsAre("doors", ""));
}

TEST(ScanBuilderTest, NamedStatesCarryGroupsOnlyWhenSomeAreSet) {
  ScanBuilder builder(10);
  builder.AddNamedState("kitchen-door", 1, "doors").AddNamedState("lab-door", 0);
  auto scan = builder.Build();
  ASSERT_TRUE(scan.ok());
  EXPECT_THAT(scan->request.named_states().names(), ElementsAre("kitchen-door", "lab-door"));
  EXPECT_THAT(scan->request.named_states().groups(), ElementsAre("doors", ""));
  ScanBuilder plain(10);
  plain.AddNamedState("x", 1);
  EXPECT_EQ(plain.Build()->request.named_states().groups_size(), 0);
}

TEST(ScanBuilderTest, PatchOfFloatsAndOfBytes) {
  ScanBuilder builder(10);
  builder.SetPatch({4, 5, 0}, {2, 3, 1}, {0, 1, 0, 1, 0, 1});
  auto floats = builder.Build();
  ASSERT_TRUE(floats.ok()) << floats.status();
  EXPECT_EQ(floats->observations, 6u);
  EXPECT_EQ(floats->request.patch().origin().x(), 4u);
  EXPECT_EQ(floats->request.patch().size().y(), 3u);
  EXPECT_EQ(floats->request.patch().values_size(), 6);

  builder.SetPatchBytes({0, 0, 0}, {2, 2, 1}, std::string("\x00\xff\x80\x01", 4));
  auto bytes = builder.Build();
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  EXPECT_EQ(bytes->request.patch().probabilities().size(), 4u);
  EXPECT_EQ(bytes->request.patch().values_size(), 0);
}

TEST(ScanBuilderTest, PatchThatDoesNotFillItsShapeIsRefused) {
  ScanBuilder builder(10);
  builder.SetPatch({0, 0, 0}, {2, 3, 1}, {0, 1});
  auto scan = builder.Build();
  EXPECT_EQ(scan.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scan.status().message(), HasSubstr("2 values for a patch of 2×3×1 = 6 cells"));
}

TEST(ScanBuilderTest, MixingKindsIsRefusedAndSaysWhatToDo) {
  ScanBuilder builder(10);
  builder.AddCell({1, 1, 0}, 1).AddPoint({1, 1, 0}, 1);
  auto scan = builder.Build();
  EXPECT_EQ(scan.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scan.status().message(), HasSubstr("this one has cells, so AddPoint needs a scan of its own"));
  ScanBuilder patches(10);
  patches.SetPatch({0, 0, 0}, {1, 1, 1}, {1}).SetPatch({0, 0, 0}, {1, 1, 1}, {1});
  EXPECT_THAT(patches.Build().status().message(), HasSubstr("one patch"));
}

TEST(ScanBuilderTest, EmptyScanAndBadTimeAreRefused) {
  ScanBuilder empty(10);
  EXPECT_THAT(empty.Build().status().message(), HasSubstr("no observations"));
  ScanBuilder nan(std::nan(""));
  nan.AddCell({0, 0, 0}, 1);
  EXPECT_THAT(nan.Build().status().message(), HasSubstr("finite"));
  ScanBuilder absurd(2e13);
  absurd.AddCell({0, 0, 0}, 1);
  EXPECT_EQ(absurd.Build().status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(ScanBuilderTest, BuildLeavesTheBuilderEmptyForTheNextScan) {
  ScanBuilder builder(10);
  builder.AddCell({1, 1, 0}, 1);
  ASSERT_TRUE(builder.Build().ok());
  EXPECT_EQ(builder.size(), 0u);
  // A failed build also resets, and the next scan may be of another kind.
  builder.AddCell({1, 1, 0}, 1).AddState(3, 1);
  EXPECT_FALSE(builder.Build().ok());
  builder.AddState(3, 1);
  auto scan = builder.Build();
  ASSERT_TRUE(scan.ok()) << scan.status();
  EXPECT_FALSE(scan->request.has_cells());
  EXPECT_DOUBLE_EQ(scan->request.time(), 10);
}

}  // namespace
}  // namespace fremen::client
