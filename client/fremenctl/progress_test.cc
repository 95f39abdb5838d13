#include "client/fremenctl/progress.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::client {
namespace {

using ::testing::HasSubstr;

v1::Operation Running(uint64_t done, uint64_t total, double rate, double eta) {
  v1::Operation op;
  op.set_name("operations/3");
  op.set_map("lab");
  op.set_stage(v1::OPERATION_STAGE_RUNNING);
  op.mutable_progress()->set_states_done(done);
  op.mutable_progress()->set_states_total(total);
  op.mutable_progress()->set_rate(rate);
  op.mutable_progress()->set_eta_seconds(eta);
  return op;
}

TEST(ProgressTest, EtaIsMinutesAndSecondsOrHours) {
  EXPECT_EQ(FormatEta(7), "0:07");
  EXPECT_EQ(FormatEta(754), "12:34");
  EXPECT_EQ(FormatEta(3723), "1:02:03");
  EXPECT_EQ(FormatEta(0), "?");
  EXPECT_EQ(FormatEta(-1), "?");
  EXPECT_EQ(FormatEta(NAN), "?");
}

TEST(ProgressTest, BarFillsWithTheShareDone) {
  EXPECT_EQ(ProgressBar(Running(1, 4, 3400, 2), 8), "[##......] 1/4 states  25% 3400 states/s ETA 0:02 (running)");
  EXPECT_THAT(ProgressBar(Running(0, 0, 0, 0), 4), HasSubstr("[....] 0/0 states   0%"));
  EXPECT_THAT(ProgressBar(Running(9, 9, 1, 0), 4), HasSubstr("[####]"));
}

TEST(ProgressTest, LineSaysTheMapStageAndFigures) {
  EXPECT_EQ(ProgressLine(Running(1200, 5000, 3400, 2.2)),
            "update of lab: running, 1200/5000 states (24%), 3400 states/s, ETA 0:02");
}

TEST(ProgressTest, SummaryOfDoneFailedAndCancelled) {
  v1::Operation op = Running(4, 4, 1, 0);
  op.set_done(true);
  op.mutable_update()->set_states_published(4);
  op.mutable_update()->set_duration_seconds(0.5);
  for (int n : {1, 3, 0}) op.mutable_update()->add_order_histogram(n);
  op.mutable_update()->set_prediction_error_before(0.3);
  op.mutable_update()->set_prediction_error_after(0.1);
  const std::string done = UpdateSummary(op);
  EXPECT_THAT(done, HasSubstr("update of lab (operations/3) done: 4 states published in 0.50 s"));
  EXPECT_THAT(done, HasSubstr("orders: 1 3 0"));
  EXPECT_THAT(done, HasSubstr("0.3000 before, 0.1000 after"));
  op.mutable_error()->set_code(1);
  op.mutable_error()->set_message("cancelled by CancelOperation");
  EXPECT_EQ(UpdateSummary(op), "update of lab (operations/3) was cancelled: cancelled by CancelOperation");
  op.mutable_error()->set_code(13);
  op.mutable_error()->set_message("disk full");
  EXPECT_EQ(UpdateSummary(op), "update of lab (operations/3) failed: disk full");
}

TEST(ProgressTest, OperationLineShowsProgressResultOrError) {
  v1::Operation op = Running(1200, 5000, 3400, 2.2);
  op.set_trigger("schedule");
  EXPECT_EQ(OperationLine(op), "operations/3 lab running: 1200/5000 states (24%) (schedule)");
  op.set_done(true);
  op.set_stage(v1::OPERATION_STAGE_DONE);
  op.set_trigger("");
  op.mutable_update()->set_states_published(5000);
  EXPECT_EQ(OperationLine(op), "operations/3 lab done: 5000 states published");
  op.mutable_error()->set_code(1);
  EXPECT_EQ(OperationLine(op), "operations/3 lab done: cancelled");
  op.mutable_error()->set_code(13);
  op.mutable_error()->set_message("disk full");
  EXPECT_EQ(OperationLine(op), "operations/3 lab done: failed: disk full");
}

}  // namespace
}  // namespace fremen::client
