// End-to-end tests of the load generators' Ingest stream (client/bench/windowed_ingest.h) against
// the real fremend: every batch is written once, in order, never more than the window
// unacknowledged, and the daemon holds every acknowledged observation; Stop ends the stream once
// the batches written are answered; a call the daemon refuses ends with its status.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "client/bench/windowed_ingest.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using bench::WindowedIngest;

constexpr double kTime = 1.7e9;
constexpr uint32_t kSide = 8;  // an 8×8 map
constexpr int kWindow = 3;

class WindowedIngestTest : public DaemonTest {
 protected:
  void SetUp() override {
    DaemonTest::SetUp();
    channel_ = daemon_->NewChannel();
    ingest_ = v1::IngestService::NewStub(channel_);
    v1::CreateMapRequest create;
    *create.mutable_map() = GridMapSpec("lab", kSide, kSide, 0.5);
    v1::CreateMapResponse created;
    const grpc::Status status = v1::MapService::NewStub(channel_)->CreateMap(CallContext().get(), create, &created);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }

  // Batch `sequence`: every cell of row sequence % kSide, occupied on odd sequences.
  v1::IngestRequest Scan(const std::string& map, uint64_t sequence) {
    v1::IngestRequest request;
    request.set_map(map);
    request.set_writer_id(11);
    request.set_sequence(sequence);
    request.set_time(kTime + 60.0 * static_cast<double>(sequence));
    v1::CellObservations& cells = *request.mutable_cells();
    for (uint32_t x = 0; x < kSide; ++x) {
      cells.mutable_cells()->add_x(x);
      cells.mutable_cells()->add_y(static_cast<uint32_t>(sequence % kSide));
      cells.mutable_cells()->add_z(0);
      cells.add_values(static_cast<float>(sequence % 2));
    }
    return request;
  }

  uint64_t StoredObservations() {
    v1::GetMapStatsRequest request;
    request.set_map("lab");
    v1::GetMapStatsResponse response;
    const grpc::Status status = v1::QueryService::NewStub(channel_)->GetMapStats(CallContext().get(), request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.stats().observations();
  }

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::IngestService::Stub> ingest_;
};

// What a stream saw: the sequences asked for and answered, and the most batches unanswered when
// the next was asked for.
struct Seen {
  std::mutex mutex;
  std::vector<uint64_t> asked, answered;
  uint64_t accepted = 0;
  int most_unanswered = 0;
  bool any_error = false;

  void Asked(uint64_t sequence) {
    std::lock_guard lock(mutex);
    asked.push_back(sequence);
    most_unanswered = std::max(most_unanswered, static_cast<int>(asked.size() - answered.size()));
  }
  void Answered(const v1::IngestResponse& ack) {
    std::lock_guard lock(mutex);
    answered.push_back(ack.sequence());
    accepted += ack.accepted();
    any_error = any_error || ack.has_error() || ack.rejected() > 0;
  }
};

TEST_F(WindowedIngestTest, EveryBatchIsWrittenOnceInOrderWithinTheWindowAndIsStored) {
  constexpr uint64_t kBatches = 60;
  Seen seen;
  v1::IngestRequest batch;
  WindowedIngest stream(
      *ingest_, CallContext(), kWindow,
      [&](uint64_t sequence) -> const v1::IngestRequest* {
        if (sequence == kBatches) return nullptr;
        seen.Asked(sequence);
        batch = Scan("lab", sequence);
        return &batch;
      },
      [&](const v1::IngestResponse& ack) { seen.Answered(ack); });
  const grpc::Status status = stream.Await();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_TRUE(stream.Ended());

  std::vector<uint64_t> in_order(kBatches);
  for (uint64_t k = 0; k < kBatches; ++k) in_order[k] = k;
  EXPECT_EQ(seen.asked, in_order);
  EXPECT_EQ(seen.answered, in_order);  // the daemon answers in batch order
  EXPECT_FALSE(seen.any_error);
  // The counter includes the batch being asked for: at most the window, and the window was used.
  EXPECT_LE(seen.most_unanswered, kWindow);
  EXPECT_GE(seen.most_unanswered, 1);
  EXPECT_EQ(seen.accepted, kBatches * kSide);
  EXPECT_EQ(StoredObservations(), kBatches * kSide);
}

TEST_F(WindowedIngestTest, StopEndsTheStreamOnceTheBatchesWrittenAreAnswered) {
  Seen seen;
  std::atomic<uint64_t> answered{0};
  v1::IngestRequest batch;
  WindowedIngest stream(
      *ingest_, CallContext(), kWindow,
      [&](uint64_t sequence) {  // never runs out
        seen.Asked(sequence);
        batch = Scan("lab", sequence);
        return &batch;
      },
      [&](const v1::IngestResponse& ack) {
        seen.Answered(ack);
        ++answered;
      });
  // Until some batches are answered (the deadline only bounds a hung daemon).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (answered < 20 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_GE(answered.load(), 20u);
  stream.Stop();
  const grpc::Status status = stream.Await();
  ASSERT_TRUE(status.ok()) << status.error_message();

  std::lock_guard lock(seen.mutex);
  EXPECT_EQ(seen.answered, seen.asked);  // nothing written is left unanswered
  EXPECT_FALSE(seen.any_error);
  EXPECT_EQ(StoredObservations(), seen.accepted);
  EXPECT_EQ(seen.accepted, seen.asked.size() * kSide);
}

TEST_F(WindowedIngestTest, ACallTheDaemonRefusesEndsWithItsStatus) {
  Seen seen;
  v1::IngestRequest batch;
  WindowedIngest stream(
      *ingest_, CallContext(), kWindow,
      [&](uint64_t sequence) {
        seen.Asked(sequence);
        batch = Scan("no-such-map", sequence);
        return &batch;
      },
      [&](const v1::IngestResponse& ack) { seen.Answered(ack); });
  const grpc::Status status = stream.Await();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
  EXPECT_NE(status.error_message().find("no-such-map"), std::string::npos) << status.error_message();
  EXPECT_TRUE(stream.Ended());
  std::lock_guard lock(seen.mutex);
  EXPECT_TRUE(seen.answered.empty());
}

}  // namespace
}  // namespace fremen::testing
