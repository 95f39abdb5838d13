// IngestStream in-process, against a store whose queue holds less than two batches: every stream
// keeps running into a full queue (Submit: ResourceExhausted), so these tests exercise the
// backpressure path — hold the batch, stop reading, resubmit from MapStore::OnRoom — which the
// end-to-end tests (tests/ingest_service_test.cc) rarely reach with the daemon's 16M-observation
// queue; the metrics see every message's bytes, every stream's end and the waits. Also: draining
// winds an idle stream down at once, and a map whose log fails (a full disk, injected) ends its
// streams at once with the storage error instead of holding them as if the queue were full.
#include "server/services/ingest_stream.h"

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "server/metrics/call_metrics.h"
#include "server/metrics/sample_lookup.h"
#include "server/services/ingest_service.h"
#include "storage/env/fault_injection_env.h"
#include "storage/store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::server {
namespace {

constexpr uint64_t kQueuedObservations = 1000;
constexpr uint32_t kCellsPerBatch = 600;  // a second batch never fits beside a first

class IngestStreamTest : public ::testing::Test {
 protected:
  void SetUp() override {
    storage::StoreOptions options;
    options.max_queued_observations = kQueuedObservations;
    disk_.set_before_sync([this]() -> absl::Status {
      return disk_full_ ? absl::ResourceExhaustedError("write to the write-ahead log: No space left on device")
                        : absl::OkStatus();
    });
    options.env = &disk_;
    auto store = storage::Store::Open(dir_.path(), options);
    ASSERT_TRUE(store.ok()) << store.status();
    store_ = *std::move(store);
    ASSERT_TRUE(store_->CreateMap(storage::testing::GridMap("lab", 64, 64, 1, 2)).ok());
    handle_.Publish(store_.get());
    service_ = std::make_unique<IngestServiceImpl>(deps_);
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(service_.get());
    server_ = builder.BuildAndStart();
    ASSERT_NE(server_, nullptr);
    stub_ = v1::IngestService::NewStub(
        grpc::CreateChannel("127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials()));
  }
  void TearDown() override {
    if (server_ != nullptr) {
      calls_.Drain(absl::Seconds(10));
      server_->Shutdown(std::chrono::system_clock::now());
    }
    if (store_ != nullptr) {
      const absl::Status closed = store_->Close();
      if (!disk_full_) {
        EXPECT_TRUE(closed.ok()) << closed;
      }
    }
  }

  static v1::IngestRequest Batch(uint64_t writer, uint64_t sequence) {
    v1::IngestRequest request;
    request.set_map("lab");
    request.set_writer_id(writer);
    request.set_sequence(sequence);
    request.set_time(1.7e9 + static_cast<double>(sequence));
    v1::CellObservations& cells = *request.mutable_cells();
    for (uint32_t i = 0; i < kCellsPerBatch; ++i) {
      cells.mutable_cells()->add_x((i + sequence) % 64);
      cells.mutable_cells()->add_y(i / 64);
      cells.add_values(i % 2);
    }
    return request;
  }

  std::atomic<bool> disk_full_ = false;  // the log's syncs fail with ENOSPC
  storage::FaultInjectionEnv disk_;      // declared before the store, so it outlives it
  fremen::testing::TempDir dir_;
  std::unique_ptr<storage::Store> store_;
  CallTracker calls_;
  Authenticator auth_{{}};
  BlockingPool blocking_{"test", 1, 16};
  StoreHandle handle_;
  prometheus::Registry registry_;
  CallMetrics metrics_{registry_};  // what the streams tell the metrics
  ServiceDeps deps_{&calls_, &auth_, &blocking_, &handle_, &metrics_};
  std::unique_ptr<IngestServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<v1::IngestService::Stub> stub_;
};

TEST_F(IngestStreamTest, StreamsWaitForRoomInTheStoreAndLoseNothing) {
  constexpr int kStreams = 4;
  constexpr uint64_t kBatches = 60;
  std::vector<std::thread> clients;
  for (int s = 0; s < kStreams; ++s) {
    clients.emplace_back([&, writer = static_cast<uint64_t>(s + 1)] {
      grpc::ClientContext context;
      auto stream = stub_->Ingest(&context);
      std::thread sender([&] {
        for (uint64_t i = 0; i < kBatches; ++i) ASSERT_TRUE(stream->Write(Batch(writer, i)));
        stream->WritesDone();
      });
      v1::IngestResponse response;
      for (uint64_t i = 0; i < kBatches; ++i) {
        ASSERT_TRUE(stream->Read(&response)) << "stream of writer " << writer << " ended at " << i;
        EXPECT_EQ(response.sequence(), i);  // in order
        EXPECT_EQ(response.accepted(), kCellsPerBatch);
        EXPECT_FALSE(response.duplicate());
        EXPECT_FALSE(response.has_error()) << response.error().message();
      }
      sender.join();
      EXPECT_FALSE(stream->Read(&response));
      EXPECT_TRUE(stream->Finish().ok());
    });
  }
  for (std::thread& c : clients) c.join();
  // Each batch was applied exactly once: a resend is a duplicate.
  auto map = store_->Map("lab");
  ASSERT_TRUE(map.ok());
  for (uint64_t writer = 1; writer <= kStreams; ++writer) {
    v1::IngestRequest again = Batch(writer, kBatches - 1);
    grpc::ClientContext context;
    auto stream = stub_->Ingest(&context);
    ASSERT_TRUE(stream->Write(again));
    v1::IngestResponse response;
    ASSERT_TRUE(stream->Read(&response));
    EXPECT_TRUE(response.duplicate());
    stream->WritesDone();
    EXPECT_TRUE(stream->Finish().ok());
  }
  // The metrics saw every message's bytes, every stream's end, and the waits for room.
  double bytes = 0;
  for (uint64_t writer = 1; writer <= kStreams; ++writer) {
    for (uint64_t i = 0; i < kBatches; ++i) bytes += static_cast<double>(Batch(writer, i).ByteSizeLong());
    bytes += static_cast<double>(Batch(writer, kBatches - 1).ByteSizeLong());  // the resend
  }
  const auto families = registry_.Collect();
  EXPECT_EQ(Sample(families, "fremen_ingest_received_bytes_total", {{"map", "lab"}}), bytes);
  EXPECT_EQ(Sample(families, "fremen_grpc_calls_total", {{"method", "Ingest"}, {"code", "OK"}}), 2 * kStreams);
  EXPECT_GT(Sample(families, "fremen_ingest_backpressure_wait_seconds_total", {{"map", "lab"}}).value_or(0), 0);
}

TEST_F(IngestStreamTest, DrainEndsAnIdleStreamAtOnceWithUnavailable) {
  grpc::ClientContext context;
  auto stream = stub_->Ingest(&context);
  ASSERT_TRUE(stream->Write(Batch(1, 0)));
  v1::IngestResponse response;
  ASSERT_TRUE(stream->Read(&response));
  EXPECT_EQ(response.accepted(), kCellsPerBatch);
  // The client now idles with its stream open.
  EXPECT_EQ(calls_.Drain(absl::Seconds(10)), 0);
  EXPECT_FALSE(stream->Read(&response));
  const grpc::Status status = stream->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_NE(status.error_message().find("shutting down"), std::string::npos) << status.error_message();
}

TEST_F(IngestStreamTest, AFullDiskEndsTheLiveStreamAndEveryNewOneAtOnceWithTheStorageError) {
  grpc::ClientContext live_context;
  auto live = stub_->Ingest(&live_context);
  ASSERT_TRUE(live->Write(Batch(1, 1)));
  v1::IngestResponse response;
  ASSERT_TRUE(live->Read(&response));
  EXPECT_EQ(response.accepted(), kCellsPerBatch);

  disk_full_ = true;
  ASSERT_TRUE(live->Write(Batch(1, 2)));
  EXPECT_FALSE(live->Read(&response));  // not durable: never acknowledged
  const grpc::Status ended = live->Finish();
  EXPECT_EQ(ended.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << ended.error_message();
  EXPECT_NE(ended.error_message().find("No space left on device"), std::string::npos) << ended.error_message();

  // A new stream on the failed map learns it from its first batch — not at its deadline, as when
  // the storage error was taken for a full queue and waited out.
  for (uint64_t writer : {1, 2}) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    auto stream = stub_->Ingest(&context);
    ASSERT_TRUE(stream->Write(Batch(writer, 3)));
    EXPECT_FALSE(stream->Read(&response));
    const grpc::Status refused = stream->Finish();
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << refused.error_message();
    EXPECT_NE(refused.error_message().find("map lab refuses writes"), std::string::npos) << refused.error_message();
  }
  auto map = store_->Map("lab");
  ASSERT_TRUE(map.ok());
  EXPECT_EQ((*map)->Stats().totals.observations, kCellsPerBatch);  // the acknowledged batch
}

}  // namespace
}  // namespace fremen::server
