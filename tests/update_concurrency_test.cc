// End-to-end: ingest and queries keep working while the update job publishes a large map
// (docs/update-job.md, "How it runs beside ingest and queries": every read sees each state's old
// model or its new one, never a mix). A 1M-cell grid whose every cell is dynamic is updated over
// RunUpdate while one client streams scans into part of the grid and another predicts the rest:
// scans are acknowledged while the operation is PUBLISHING, and every prediction read is the cell's
// value before the job or after it. The daemon runs with test_publication_waits_for_a_batch, so
// that "while" is decided by order, not by timing: the publication starts and then waits for a
// batch, so a prediction answered then, and the scan that releases it, were served during it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"
#include "tests/store_writer.h"

namespace fremen::testing {
namespace {

constexpr double kT0 = 1'700'006'400;
constexpr uint32_t kNx = 1024, kNy = 1024;  // 1,048,576 dynamic cells: the job takes a while
constexpr uint32_t kIngestRows = 64;        // the ingest client writes rows [0, 64)

class UpdateConcurrencyTest : public DaemonTest {
 protected:
  void SetUp() override {
    StartDaemon({"--update-schedule", ""});
    if (HasFatalFailure()) return;
    v1::CreateMapRequest create;
    *create.mutable_map() = GridMapSpec("big", kNx, kNy, 0.05);
    // One shard: the publication runs on one thread, so that it lasts many scan round trips.
    create.mutable_map()->set_shards(1);
    v1::CreateMapResponse created;
    const grpc::Status status =
        v1::MapService::NewStub(daemon_->NewChannel())->CreateMap(CallContext().get(), create, &created);
    ASSERT_TRUE(status.ok()) << status.error_message();
    StopDaemon();
    const absl::Status written = WriteBatches(data_dir(), "big",
                                              {GridScan(kNx, kNy, kT0, 0.0f), GridScan(kNx, kNy, kT0 + 3600, 1.0f),
                                               GridScan(kNx, kNy, kT0 + 7200, 0.0f)});
    ASSERT_TRUE(written.ok()) << written;
    StartDaemon({"--update-schedule", "", "--test-publication-waits-for-a-batch=true"});
  }
};

// A scan of the ingest rows, every cell `value`, as a dense patch.
v1::IngestRequest IngestScan(uint64_t sequence, double t, float value) {
  v1::IngestRequest request;
  request.set_map("big");
  request.set_writer_id(7);
  request.set_sequence(sequence);
  request.set_time(t);
  v1::DensePatch& patch = *request.mutable_patch();
  patch.mutable_size()->set_x(kNx);
  patch.mutable_size()->set_y(kIngestRows);
  patch.mutable_size()->set_z(1);
  patch.mutable_values()->Resize(kNx * kIngestRows, value);
  return request;
}

// Whether `op` shows its publication started and held before its first slice: the map has counted
// the states to publish (it reports 0 of them done when the publication begins) and, waiting for a
// batch, published none.
bool PublicationHeld(const v1::Operation& op) {
  return !op.done() && op.stage() == v1::OPERATION_STAGE_PUBLISHING && op.progress().states_total() > 0 &&
         op.progress().states_done() == 0;
}

TEST_F(UpdateConcurrencyTest, IngestAndQueriesContinueWhileTheJobPublishes) {
  auto admin = v1::AdminService::NewStub(daemon_->NewChannel());
  auto query = v1::QueryService::NewStub(daemon_->NewChannel());
  auto ingest = v1::IngestService::NewStub(daemon_->NewChannel());

  // Watched cells: outside the ingest rows, so only the job changes their predictions.
  v1::PredictRequest predict;
  predict.set_map("big");
  for (uint32_t y = kIngestRows; y < kNy; y += 37) {
    for (uint32_t x = 0; x < kNx; x += 29) {
      predict.mutable_states()->mutable_cells()->add_x(x);
      predict.mutable_states()->mutable_cells()->add_y(y);
      predict.mutable_states()->mutable_cells()->add_z(0);
    }
  }
  predict.add_times(kT0 + 5 * 3600);
  // One prediction of the watched cells; the call's status is the caller's to check.
  const auto read = [&](v1::QueryService::Stub& stub, std::vector<float>* out) {
    v1::PredictResponse response;
    const grpc::Status status = stub.Predict(CallContext().get(), predict, &response);
    out->assign(response.probabilities().begin(), response.probabilities().end());
    return status;
  };
  std::vector<float> before;
  const grpc::Status read_before = read(*query, &before);
  ASSERT_TRUE(read_before.ok()) << read_before.error_message();
  ASSERT_EQ(before.size(), static_cast<size_t>(predict.states().cells().x_size()));

  v1::RunUpdateRequest run;
  run.set_map("big");
  v1::Operation op;
  ASSERT_TRUE(admin->RunUpdate(CallContext().get(), run, &op).ok());
  v1::GetOperationRequest get;
  get.set_name(op.name());
  const auto look = [&](v1::Operation* seen) {
    const grpc::Status status = admin->GetOperation(CallContext().get(), get, seen);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return status.ok();
  };

  // The job computes its statistics, then starts publishing and waits for a batch: nothing else
  // writes to the map, so it stays there until the first scan below.
  const auto held_deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  while (look(&op) && !PublicationHeld(op) && !op.done() && std::chrono::steady_clock::now() < held_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(PublicationHeld(op)) << "the publication was not seen waiting: " << op.DebugString();
  // A prediction answered now was answered during the publication: it is still held afterwards.
  std::vector<float> during;
  const grpc::Status read_during = read(*query, &during);
  ASSERT_TRUE(read_during.ok()) << read_during.error_message();
  ASSERT_TRUE(look(&op));
  EXPECT_TRUE(PublicationHeld(op)) << "the publication went on without a batch: " << op.DebugString();
  EXPECT_EQ(during, before) << "a prediction during the publication, before its first slice, changed";

  // The reader predicts the watched cells until the job has ended, while the publication runs its
  // slices. It keeps what it read and the first failed call: both checked once it has been joined.
  std::atomic<bool> done = false;
  std::vector<std::vector<float>> reads;
  grpc::Status failed_read;
  std::thread reader([&, stub = v1::QueryService::NewStub(daemon_->NewChannel())] {
    while (!done) {
      std::vector<float> r;
      const grpc::Status status = read(*stub, &r);
      if (!status.ok()) {
        failed_read = status;
        break;
      }
      reads.push_back(std::move(r));
    }
  });

  // This thread writes one scan at a time, waiting for each ack, until the job has ended. The first
  // scan is sent while the publication is held, and the publication cannot go on until a batch has
  // been applied and acknowledged: its ack comes during the publication by construction (a daemon
  // that held writes back until a publication's end would never answer it: the stream's deadline
  // would end the test).
  int failed_acks = 0;
  uint64_t acks = 0;
  grpc::Status polled;
  std::string stream_broke;
  {
    auto context = CallContext({}, std::chrono::seconds(300));
    auto stream = ingest->Ingest(context.get());
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
    for (uint64_t i = 1; !op.done() && std::chrono::steady_clock::now() < deadline; ++i) {
      v1::IngestResponse ack;
      if (!stream->Write(IngestScan(i, kT0 + 10800 + 60.0 * i, static_cast<float>(i % 2))) || !stream->Read(&ack)) {
        stream_broke = "the ingest stream ended at scan " + std::to_string(i);
        break;
      }
      ++acks;
      if (ack.error().code() != 0 || ack.accepted() != kNx * kIngestRows) ++failed_acks;
      polled = admin->GetOperation(CallContext().get(), get, &op);
      if (!polled.ok()) break;
    }
    stream->WritesDone();
    v1::IngestResponse rest;
    while (stream->Read(&rest)) {
    }
    const grpc::Status finished = stream->Finish();
    if (stream_broke.empty() && !finished.ok()) stream_broke = finished.error_message();
  }
  done = true;
  reader.join();
  ASSERT_TRUE(polled.ok()) << polled.error_message();
  ASSERT_EQ(stream_broke, "");
  ASSERT_TRUE(failed_read.ok()) << failed_read.error_message();
  ASSERT_TRUE(op.done()) << "the update did not finish in 3 minutes";
  ASSERT_EQ(op.error().code(), 0) << op.error().message();
  EXPECT_EQ(op.update().states_published(), kNx * kNy);

  std::vector<float> after;
  const grpc::Status read_after = read(*query, &after);
  ASSERT_TRUE(read_after.ok()) << read_after.error_message();
  size_t torn = 0;
  for (const std::vector<float>& r : reads) {
    ASSERT_EQ(r.size(), before.size());
    for (size_t j = 0; j < r.size(); ++j) torn += r[j] != before[j] && r[j] != after[j];
  }
  EXPECT_EQ(torn, 0u) << "a prediction was neither the cell's old one nor its new one";
  EXPECT_EQ(failed_acks, 0);
  EXPECT_GE(acks, 1u);
  std::printf("%llu scans acknowledged, the first while the publication waited for it; %zu reads while it ran\n",
              static_cast<unsigned long long>(acks), reads.size());
}

}  // namespace
}  // namespace fremen::testing
