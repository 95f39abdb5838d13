// The metrics against real components: a real store in a temp dir, observed by Metrics, takes
// batches (one repeated: a duplicate), checkpoints and is scraped — the ingest, log, checkpoint,
// recovery and per-map families carry what happened; before the store is open only fremen_maps 0
// is exported. Call, ingest-byte and job metrics count what they are told; the text format names
// every family with its type.
#include "server/metrics/metrics.h"

#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "server/metrics/sample_lookup.h"
#include "storage/store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::server {
namespace {

using Labels = SampleLabels;

TEST(MetricsTest, StoreWritesAndMapsAreExported) {
  Metrics metrics;
  StoreHandle handle;
  metrics.Watch(&handle, nullptr);
  EXPECT_EQ(Sample(metrics.Collect(), "fremen_maps"), 0);  // recovering: no store yet
  EXPECT_EQ(Sample(metrics.Collect(), "fremen_map_states", {{"map", "lab"}}), std::nullopt);

  fremen::testing::TempDir dir;
  storage::StoreOptions options;
  options.observer = metrics.store();
  auto store = storage::Store::Open(dir.path(), options);
  ASSERT_TRUE(store.ok()) << store.status();
  auto info = (*store)->CreateMap(storage::testing::GridMap("lab", 32, 32, 1, 2));
  ASSERT_TRUE(info.ok()) << info.status();
  handle.Publish(store->get());
  auto map = (*store)->Map("lab");
  ASSERT_TRUE(map.ok()) << map.status();
  uint64_t accepted = 0;
  for (uint64_t i = 0; i < 3; ++i) {
    auto ack = (*map)->Write(storage::testing::SweepScan(*info, 1, i, 200));
    ASSERT_TRUE(ack.ok()) << ack.status();
    accepted += ack->accepted;
  }
  auto repeat = (*map)->Write(storage::testing::SweepScan(*info, 1, 2, 200));  // a retry of the last
  ASSERT_TRUE(repeat.ok()) << repeat.status();
  ASSERT_TRUE(repeat->duplicate);
  ASSERT_TRUE((*map)->Checkpoint().ok());

  const auto families = metrics.Collect();
  const Labels lab = {{"map", "lab"}};
  EXPECT_EQ(Sample(families, "fremen_ingest_observations_total", lab), accepted);
  EXPECT_EQ(Sample(families, "fremen_ingest_rejected_observations_total", lab), 0);
  EXPECT_EQ(Sample(families, "fremen_ingest_batches_total", {{"map", "lab"}, {"result", "applied"}}), 3);
  EXPECT_EQ(Sample(families, "fremen_ingest_batches_total", {{"map", "lab"}, {"result", "duplicate"}}), 1);
  EXPECT_EQ(Sample(families, "fremen_ingest_batches_total", {{"map", "lab"}, {"result", "refused"}}), 0);
  EXPECT_EQ(Sample(families, "fremen_log_appends_total", lab), 3);  // the duplicate is not logged
  const double fsyncs = Sample(families, "fremen_log_fsyncs_total", lab).value_or(0);
  EXPECT_GE(fsyncs, 1);
  EXPECT_LE(fsyncs, 3);
  EXPECT_EQ(Sample(families, "fremen_log_fsync_duration_seconds", lab), fsyncs);
  EXPECT_EQ(Sample(families, "fremen_log_group_records", lab), fsyncs);
  EXPECT_GE(Sample(families, "fremen_checkpoints_total", lab).value_or(0), 1);
  EXPECT_GT(Sample(families, "fremen_checkpoint_bytes_total", lab).value_or(0), 0);
  EXPECT_TRUE(Sample(families, "fremen_recovery_duration_seconds", lab).has_value());

  const storage::MapStats stats = (*map)->Stats();  // what GetMapStats answers
  EXPECT_EQ(Sample(families, "fremen_maps"), 1);
  EXPECT_EQ(Sample(families, "fremen_failed_maps"), 0);
  EXPECT_EQ(Sample(families, "fremen_map_observations", lab), accepted);
  EXPECT_EQ(Sample(families, "fremen_map_states", lab), stats.totals.states);
  EXPECT_EQ(Sample(families, "fremen_map_dynamic_states", lab), stats.totals.dynamic_states);
  EXPECT_EQ(Sample(families, "fremen_map_disk_bytes", lab), stats.totals.disk_bytes);
  EXPECT_EQ(Sample(families, "fremen_map_compression_ratio", lab), stats.compression_ratio);
  EXPECT_EQ(Sample(families, "fremen_map_prediction_error", lab), stats.mean_prediction_error);
  EXPECT_EQ(Sample(families, "fremen_ingest_queued_observations", lab), 0);
  EXPECT_EQ(Sample(families, "fremen_lmdb_map_size_bytes", lab), 2.0 * storage::StoreOptions().initial_map_size);
  EXPECT_EQ(Sample(families, "fremen_lmdb_growths_total", lab), 0);
  EXPECT_TRUE(Sample(families, "fremen_lmdb_readers", lab).has_value());
  EXPECT_TRUE((*store)->Close().ok());
}

TEST(MetricsTest, CallsAndIngestBytesAreCountedByMethodAndCode) {
  Metrics metrics;
  metrics.calls()->CallFinished("GetMap", grpc::StatusCode::OK, absl::Milliseconds(1));
  metrics.calls()->CallFinished("GetMap", grpc::StatusCode::NOT_FOUND, absl::Milliseconds(2));
  metrics.calls()->CallFinished("GetMap", grpc::StatusCode::NOT_FOUND, absl::Milliseconds(3));
  metrics.calls()->IngestReceived("lab", 100);
  metrics.calls()->IngestReceived("lab", 20);
  metrics.calls()->IngestWaited("lab", absl::Milliseconds(250));
  const auto families = metrics.Collect();
  EXPECT_EQ(Sample(families, "fremen_grpc_calls_total", {{"method", "GetMap"}, {"code", "OK"}}), 1);
  EXPECT_EQ(Sample(families, "fremen_grpc_calls_total", {{"method", "GetMap"}, {"code", "NOT_FOUND"}}), 2);
  EXPECT_EQ(Sample(families, "fremen_grpc_call_duration_seconds", {{"method", "GetMap"}}), 3);
  EXPECT_EQ(Sample(families, "fremen_ingest_received_bytes_total", {{"map", "lab"}}), 120);
  EXPECT_DOUBLE_EQ(Sample(families, "fremen_ingest_backpressure_wait_seconds_total", {{"map", "lab"}}).value_or(0),
                   0.25);
}

TEST(MetricsTest, UpdateJobsAreCountedByResult) {
  Metrics metrics;
  OperationView done;
  done.map = "lab";
  done.stage = OperationStage::kDone;
  done.result = UpdateFigures{};
  done.result->states_published = 40;
  done.result->duration = absl::Seconds(2);
  metrics.jobs()->Finished(done);
  OperationView cancelled;
  cancelled.stage = OperationStage::kDone;
  cancelled.error = absl::CancelledError("cancelled before it started");
  metrics.jobs()->Finished(cancelled);
  OperationView failed;
  failed.stage = OperationStage::kDone;
  failed.error = absl::DataLossError("shard-0/data.mdb: damaged");
  metrics.jobs()->Finished(failed);
  const auto families = metrics.Collect();
  EXPECT_EQ(Sample(families, "fremen_update_jobs_total", {{"result", "ok"}}), 1);
  EXPECT_EQ(Sample(families, "fremen_update_jobs_total", {{"result", "cancelled"}}), 1);
  EXPECT_EQ(Sample(families, "fremen_update_jobs_total", {{"result", "failed"}}), 1);
  EXPECT_EQ(Sample(families, "fremen_update_job_duration_seconds"), 1);
  EXPECT_EQ(Sample(families, "fremen_update_states_published_total"), 40);
}

TEST(MetricsTest, TextFormatTypesEveryFamily) {
  Metrics metrics;
  StoreHandle handle;
  metrics.Watch(&handle, nullptr);
  metrics.calls()->CallFinished("ListMaps", grpc::StatusCode::OK, absl::Milliseconds(1));
  const std::string text = metrics.Scrape();
  EXPECT_NE(text.find("# TYPE fremen_grpc_calls_total counter"), std::string::npos) << text;
  EXPECT_NE(text.find("# TYPE fremen_grpc_call_duration_seconds histogram"), std::string::npos) << text;
  EXPECT_NE(text.find("# TYPE fremen_maps gauge"), std::string::npos) << text;
  EXPECT_NE(text.find("fremen_grpc_calls_total{code=\"OK\",method=\"ListMaps\"} 1"), std::string::npos) << text;
}

}  // namespace
}  // namespace fremen::server
