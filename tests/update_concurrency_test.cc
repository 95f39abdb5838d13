// End-to-end: ingest and queries keep working while the update job publishes a large map
// (docs/update-job.md, "How it runs beside ingest and queries": every read sees each state's old
// model or its new one, never a mix). A 1M-cell grid whose every cell is dynamic is updated over
// RunUpdate while one client streams scans into part of the grid and another predicts the rest:
// scans are acknowledged while the operation is PUBLISHING, and every prediction read is the cell's
// value before the job or after it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
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

// Whether `op` shows a publication under way: its first slice published (states_done > 0: the map
// reports progress from the thread that applies batches, after each slice) and its last not yet.
bool MidPublication(const v1::Operation& op) {
  return !op.done() && op.stage() == v1::OPERATION_STAGE_PUBLISHING && op.progress().states_done() > 0 &&
         op.progress().states_done() < op.progress().states_total();
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

  // The reader predicts the watched cells until the job has ended, looking at the operation before
  // each call and after its answer (as the writer below does for its scans). It keeps what it read,
  // how many answers came between two looks that showed the publication under way, and the first
  // failed call: all checked once it has been joined.
  std::atomic<bool> done = false;
  std::vector<std::vector<float>> reads;
  int reads_within_publication = 0;
  grpc::Status failed_read;
  std::thread reader([&, stub = v1::QueryService::NewStub(daemon_->NewChannel()),
                      admin_stub = v1::AdminService::NewStub(daemon_->NewChannel()), name = op.name()] {
    v1::GetOperationRequest get;
    get.set_name(name);
    v1::Operation seen;
    bool publishing_before = false;
    while (!done) {
      std::vector<float> r;
      grpc::Status status = read(*stub, &r);
      if (status.ok()) status = admin_stub->GetOperation(CallContext().get(), get, &seen);
      if (!status.ok()) {
        failed_read = status;
        break;
      }
      reads.push_back(std::move(r));
      const bool publishing_after = MidPublication(seen);
      if (publishing_before && publishing_after) ++reads_within_publication;
      publishing_before = publishing_after;
    }
  });

  // This thread writes one scan at a time and looks at the operation before sending it and after
  // its ack has come back. An ack seen between two looks that both show the publication under way
  // was applied and acknowledged while it ran: a publication that held the map's writes up until
  // its end would leave none, however fast or slow the machine (its last progress report, all
  // states done, comes before any held batch is applied).
  int acks_within_publication = 0, failed_acks = 0;
  uint64_t acks = 0;
  grpc::Status polled;
  std::string stream_broke;
  {
    auto context = CallContext({}, std::chrono::seconds(300));
    auto stream = ingest->Ingest(context.get());
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
    for (uint64_t i = 1; !op.done() && std::chrono::steady_clock::now() < deadline; ++i) {
      const bool publishing_before = MidPublication(op);
      v1::IngestResponse ack;
      if (!stream->Write(IngestScan(i, kT0 + 10800 + 60.0 * i, static_cast<float>(i % 2))) || !stream->Read(&ack)) {
        stream_broke = "the ingest stream ended at scan " + std::to_string(i);
        break;
      }
      ++acks;
      if (ack.error().code() != 0 || ack.accepted() != kNx * kIngestRows) ++failed_acks;
      v1::GetOperationRequest get;
      get.set_name(op.name());
      polled = admin->GetOperation(CallContext().get(), get, &op);
      if (!polled.ok()) break;
      if (publishing_before && MidPublication(op)) ++acks_within_publication;
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
  std::printf("%llu scans acknowledged, %d of them within the publication; %d reads within it\n",
              static_cast<unsigned long long>(acks), acks_within_publication, reads_within_publication);
  EXPECT_GT(acks_within_publication, 0) << "no scan was acknowledged while the job published";
  EXPECT_GT(reads_within_publication, 0) << "no prediction was answered while the job published";
}

}  // namespace
}  // namespace fremen::testing
