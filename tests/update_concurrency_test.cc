// End-to-end: ingest and queries keep working while the update job publishes a large map
// (docs/update-job.md, "How it runs beside ingest and queries": every read sees each state's old
// model or its new one, never a mix). A 1M-cell grid whose every cell is dynamic is updated over
// RunUpdate while one client streams scans into part of the grid and another predicts the rest:
// scans are acknowledged while the operation is PUBLISHING, and every prediction read is the cell's
// value before the job or after it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
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
    create.mutable_map()->set_name("big");
    create.mutable_map()->set_kind(v1::MAP_KIND_GRID);
    create.mutable_map()->mutable_grid()->set_resolution(0.05);
    create.mutable_map()->mutable_grid()->mutable_size()->set_x(kNx);
    create.mutable_map()->mutable_grid()->mutable_size()->set_y(kNy);
    v1::CreateMapResponse created;
    const grpc::Status status =
        v1::MapService::NewStub(daemon_->NewChannel())->CreateMap(CallContext().get(), create, &created);
    ASSERT_TRUE(status.ok()) << status.error_message();
    StopDaemon();
    const absl::Status written = WriteBatches(data_dir(), "big",
                                              {GridScan(kNx, kNy, kT0, 0.0f), GridScan(kNx, kNy, kT0 + 3600, 1.0f),
                                               GridScan(kNx, kNy, kT0 + 7200, 0.0f)});
    ASSERT_TRUE(written.ok()) << written;
    StartDaemon({"--update-schedule", ""});
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
  const auto read = [&](v1::QueryService::Stub& stub) {
    v1::PredictResponse response;
    const grpc::Status status = stub.Predict(CallContext().get(), predict, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return std::vector<float>(response.probabilities().begin(), response.probabilities().end());
  };
  const std::vector<float> before = read(*query);
  ASSERT_EQ(before.size(), static_cast<size_t>(predict.states().cells().x_size()));

  v1::RunUpdateRequest run;
  run.set_map("big");
  v1::Operation op;
  ASSERT_TRUE(admin->RunUpdate(CallContext().get(), run, &op).ok());

  std::atomic<bool> publishing = false, done = false;
  std::atomic<int> acks_while_publishing = 0, failed_acks = 0;
  std::thread writer([&] {
    auto context = CallContext({}, std::chrono::seconds(300));
    auto stream = ingest->Ingest(context.get());
    for (uint64_t i = 1; !done; ++i) {
      if (!stream->Write(IngestScan(i, kT0 + 10800 + 60.0 * i, static_cast<float>(i % 2)))) break;
      v1::IngestResponse ack;
      if (!stream->Read(&ack)) break;
      if (ack.error().code() != 0 || ack.accepted() != kNx * kIngestRows) ++failed_acks;
      if (publishing && !done) ++acks_while_publishing;
    }
    stream->WritesDone();
    v1::IngestResponse rest;
    while (stream->Read(&rest)) {
    }
    const grpc::Status status = stream->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
  });
  std::vector<std::vector<float>> reads;
  std::thread reader([&, stub = v1::QueryService::NewStub(daemon_->NewChannel())] {
    while (!done) reads.push_back(read(*stub));
  });

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  while (!op.done() && std::chrono::steady_clock::now() < deadline) {
    v1::GetOperationRequest get;
    get.set_name(op.name());
    const grpc::Status polled = admin->GetOperation(CallContext().get(), get, &op);
    EXPECT_TRUE(polled.ok()) << polled.error_message();
    if (!polled.ok()) break;  // the threads are joined below before any assertion returns
    if (op.stage() == v1::OPERATION_STAGE_PUBLISHING) publishing = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling a real daemon
  }
  done = true;
  writer.join();
  reader.join();
  ASSERT_TRUE(op.done()) << "the update did not finish in 3 minutes";
  ASSERT_EQ(op.error().code(), 0) << op.error().message();
  EXPECT_EQ(op.update().states_published(), kNx * kNy);

  const std::vector<float> after = read(*query);
  size_t torn = 0;
  for (const std::vector<float>& r : reads) {
    ASSERT_EQ(r.size(), before.size());
    for (size_t j = 0; j < r.size(); ++j) torn += r[j] != before[j] && r[j] != after[j];
  }
  EXPECT_EQ(torn, 0u) << "a prediction was neither the cell's old one nor its new one";
  EXPECT_GT(reads.size(), 1u);
  EXPECT_EQ(failed_acks, 0);
  // The writer has one scan in flight: a publication that held the map's writes up until it ended
  // would let one or two acks land in the window; served in slices, it lets through one per scan.
  EXPECT_GE(acks_while_publishing, 3) << "scans were not acknowledged while the job published";
}

}  // namespace
}  // namespace fremen::testing
