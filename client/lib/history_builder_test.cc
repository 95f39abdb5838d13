#include "client/lib/history_builder.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace fremen::client {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(HistoryBuilderTest, OneStatesHistorySendsItsIdOnce) {
  HistoryBuilder builder = HistoryBuilder::ForId(42, "front door", "doors");
  builder.Add(1.7e9, 1).Add(1.7e9 + 60, 0);
  EXPECT_EQ(builder.size(), 2u);
  auto batch = builder.Build();
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_EQ(batch->observations, 2u);
  const v1::HistoryObservations& h = batch->request.history();
  EXPECT_THAT(h.ids(), ElementsAre(42u));
  EXPECT_THAT(h.names(), ElementsAre("front door"));
  EXPECT_THAT(h.groups(), ElementsAre("doors"));
  EXPECT_THAT(h.times(), ElementsAre(1.7e9, 1.7e9 + 60));
  EXPECT_THAT(h.values(), ElementsAre(1.0f, 0.0f));
  EXPECT_EQ(batch->request.time(), 0.0) << "a history's request time stays unset";
  // The next batch is of the same state.
  builder.Add(1.7e9 + 120, 1);
  auto next = builder.Build();
  ASSERT_TRUE(next.ok()) << next.status();
  EXPECT_THAT(next->request.history().ids(), ElementsAre(42u));
  EXPECT_THAT(next->request.history().times(), ElementsAre(1.7e9 + 120));
}

TEST(HistoryBuilderTest, ANamedStatesHistoryHasNoIds) {
  HistoryBuilder builder = HistoryBuilder::ForName("door");
  auto batch = builder.Add(5, 1).Build();
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_TRUE(batch->request.history().ids().empty());
  EXPECT_THAT(batch->request.history().names(), ElementsAre("door"));
  EXPECT_TRUE(batch->request.history().groups().empty());
}

TEST(HistoryBuilderTest, ManyStatesTakeAnIdPerObservation) {
  HistoryBuilder builder;
  auto batch = builder.AddState(5, 1, 1).AddState(5, 2, 0).Build();
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_THAT(batch->request.history().ids(), ElementsAre(1u, 2u));
  EXPECT_THAT(batch->request.history().times(), ElementsAre(5.0, 5.0));
}

TEST(HistoryBuilderTest, MistakesAreInvalidArgumentAndLeaveTheBuilderEmpty) {
  HistoryBuilder many;
  EXPECT_THAT(many.Build().status().message(), HasSubstr("no observations"));
  EXPECT_THAT(many.Add(1, 1).Build().status().message(), HasSubstr("use AddState"));
  HistoryBuilder one = HistoryBuilder::ForId(1);
  EXPECT_THAT(one.AddState(1, 2, 1).Build().status().message(), HasSubstr("use Add"));
  auto bad = one.Add(1, 1).Add(NAN, 1).Build();
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("time 1 is nan"));
  EXPECT_EQ(one.size(), 0u);
  EXPECT_TRUE(one.Add(2, 1).Build().ok());
}

}  // namespace
}  // namespace fremen::client
