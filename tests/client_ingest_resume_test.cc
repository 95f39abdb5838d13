// The C++ client's ingest session across daemon restarts: batches keep flowing through a SIGTERM
// restart and a kill -9 on the same address, the session reconnects and resends what was not
// acknowledged, and in the end every batch is applied exactly once — checked through the
// per-state observation counts (GetStateModel) and the map's total (GetMapStats). And a writer
// that reboots and lost its count: a new session continues after its last sequence.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <thread>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/lib/client.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Client;
using ::fremen::client::ConnectionOptions;
using ::fremen::client::IngestSession;
using ::fremen::client::ScanBuilder;
using ::fremen::client::State;

constexpr double kStart = 1.7e9;
constexpr uint64_t kStates = 8;
constexpr int kBatchesPerPhase = 150;

class ClientIngestResumeTest : public DaemonTest {
 protected:
  void SetUp() override {
    address_ = FreeLoopbackAddress();
    StartDaemon({"--listen", address_});
    if (HasFatalFailure()) return;
    ConnectionOptions options;
    options.address = address_;
    // Quick retries: the daemon is back within a second or two.
    options.retry.max_backoff = absl::Milliseconds(250);
    client_.emplace(*Client::Connect(options));
    v1::Map map = GenericMapSpec("doors");
    map.set_shards(2);
    ASSERT_TRUE(client_->CreateMap(map).ok());
  }

  // Sends batches [from, to): batch i observes every state at time kStart + 60 i. The first failed
  // send, naming its batch; a status rather than an assertion, as a sender thread calls it too.
  static absl::Status SendBatches(IngestSession& session, int from, int to) {
    for (int i = from; i < to; ++i) {
      ScanBuilder scan(kStart + 60.0 * i);
      for (uint64_t id = 1; id <= kStates; ++id) scan.AddState(id, static_cast<float>((i + id) % 2));
      auto sent = session.Send(*scan.Build());
      if (!sent.ok()) return absl::Status(sent.status().code(), absl::StrCat("batch ", i, ": ", sent.status().message()));
    }
    return absl::OkStatus();
  }

  std::string address_;
  std::optional<Client> client_;
};

TEST_F(ClientIngestResumeTest, EveryBatchIsAppliedExactlyOnceAcrossRestartsAndAKill) {
  // A small window, so that batches are in flight whenever the daemon goes away.
  client::IngestOptions options;
  options.max_unacknowledged = 16;
  options.collect_acks = false;
  auto session = client_->OpenIngest("doors", options);
  ASSERT_TRUE(session.ok()) << session.status();

  ASSERT_EQ(SendBatches(**session, 0, kBatchesPerPhase), absl::OkStatus());
  // Batches in flight when the daemon goes away: what the session must resend.
  size_t in_flight = (*session)->unacknowledged();
  // SIGTERM: the daemon answers what it has, ends the stream with UNAVAILABLE and exits.
  StopDaemon();
  StartDaemon({"--listen", address_});
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_EQ(SendBatches(**session, kBatchesPerPhase, 2 * kBatchesPerPhase), absl::OkStatus());
  // kill -9 with batches in flight: some were applied but not acknowledged (resent, recognised as
  // duplicates), some never reached the store (resent, applied).
  in_flight += (*session)->unacknowledged();
  daemon_->Kill();
  daemon_.reset();
  StartDaemon({"--listen", address_});
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_EQ(SendBatches(**session, 2 * kBatchesPerPhase, 3 * kBatchesPerPhase), absl::OkStatus());
  ASSERT_TRUE((*session)->Close(absl::Seconds(120)).ok());

  const auto totals = (*session)->totals();
  constexpr uint64_t kBatches = 3 * kBatchesPerPhase;
  EXPECT_EQ(totals.sent, kBatches);
  EXPECT_EQ(totals.acknowledged, kBatches);
  EXPECT_EQ(totals.refused, 0u);
  EXPECT_GE(totals.reconnects, 2u) << "the session never had to reconnect: the restarts were not seen";
  EXPECT_GT(in_flight, 0u) << "no batch was in flight at either restart: nothing was resent";
  std::printf("in flight at the restarts: %zu, duplicates: %llu, reconnects: %llu\n", in_flight,
              static_cast<unsigned long long>(totals.duplicates), static_cast<unsigned long long>(totals.reconnects));
  // Duplicates were answered but not applied: accepted + duplicates' observations = all.
  EXPECT_EQ(totals.accepted + totals.duplicates * kStates, kBatches * kStates);

  for (uint64_t id = 1; id <= kStates; ++id) {
    auto model = client_->GetStateModel("doors", State::WithId(id));
    ASSERT_TRUE(model.ok()) << model.status();
    ASSERT_TRUE(model->has_value()) << "state " << id;
    EXPECT_EQ((*model)->observations(), kBatches) << "state " << id << " lost or repeated batches";
    EXPECT_DOUBLE_EQ((*model)->last_time(), kStart + 60.0 * (kBatches - 1));
  }
  auto stats = client_->GetMapStats("doors");
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->observations(), kBatches * kStates);
}

TEST_F(ClientIngestResumeTest, ARebootedWriterContinuesAfterItsLastSequenceAndLosesNothing) {
  client::IngestOptions options;
  options.writer_id = 42;  // the robot's fixed id; its sequence counter is lost at every reboot
  {
    auto session = client_->OpenIngest("doors", options);
    ASSERT_TRUE(session.ok()) << session.status();
    EXPECT_EQ((*session)->first_sequence(), 1u);
    ASSERT_EQ(SendBatches(**session, 0, 10), absl::OkStatus());
    ASSERT_TRUE((*session)->Close(absl::Seconds(60)).ok());
  }
  // Rebooted, and the daemon restarted meanwhile too: the session asks where to continue.
  StopDaemon();
  StartDaemon({"--listen", address_});
  ASSERT_FALSE(HasFatalFailure());
  auto rebooted = client_->OpenIngest("doors", options);
  ASSERT_TRUE(rebooted.ok()) << rebooted.status();
  EXPECT_EQ((*rebooted)->first_sequence(), 11u);
  ASSERT_EQ(SendBatches(**rebooted, 10, 20), absl::OkStatus());
  ASSERT_TRUE((*rebooted)->Close(absl::Seconds(60)).ok());
  const auto totals = (*rebooted)->totals();
  EXPECT_EQ(totals.acknowledged, 10u);
  EXPECT_EQ(totals.duplicates, 0u);
  EXPECT_EQ(totals.refused, 0u);
  for (uint64_t id = 1; id <= kStates; ++id) {
    auto model = client_->GetStateModel("doors", State::WithId(id));
    ASSERT_TRUE(model.ok()) << model.status();
    ASSERT_TRUE(model->has_value()) << "state " << id;
    EXPECT_EQ((*model)->observations(), 20u) << "state " << id;
  }

  // Told to count from 1 again, a session's new batches are refused naming where to continue —
  // never acknowledged as duplicates and dropped.
  options.first_sequence = 1;
  auto counting_again = client_->OpenIngest("doors", options);
  ASSERT_TRUE(counting_again.ok()) << counting_again.status();
  ASSERT_EQ(SendBatches(**counting_again, 20, 21), absl::OkStatus());
  ASSERT_TRUE((*counting_again)->Close(absl::Seconds(60)).ok());
  const std::vector<client::IngestAck> acks = (*counting_again)->TakeAcks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_FALSE(acks[0].duplicate);
  EXPECT_EQ(acks[0].error.code(), absl::StatusCode::kAlreadyExists) << acks[0].error;
  EXPECT_THAT(acks[0].error.message(),
              ::testing::HasSubstr("writer 42 sequence 1 was already used for a different batch; continue after "
                                   "sequence 20"));
  auto stats = client_->GetMapStats("doors");
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->observations(), 20 * kStates);
}

TEST_F(ClientIngestResumeTest, ASenderThreadKeepsSendingThroughAKillAndARestart) {
  // Here the batches come from another thread while this one kills and restarts the daemon: Send
  // blocks during the outage (the window is full) and resumes once the session has reconnected.
  client::IngestOptions options;
  options.max_unacknowledged = 16;
  options.collect_acks = false;
  auto session = client_->OpenIngest("doors", options);
  ASSERT_TRUE(session.ok()) << session.status();
  constexpr int kBatches = 4 * kBatchesPerPhase;
  absl::Status sent;  // the sender's, read once it has been joined
  std::thread sender([&] { sent = SendBatches(**session, 0, kBatches); });
  const auto await_acks = [&](uint64_t n) {
    const absl::Time give_up = absl::Now() + absl::Seconds(120);
    while ((*session)->totals().acknowledged < n && absl::Now() < give_up) absl::SleepFor(absl::Milliseconds(1));
    // Without this the daemon would be killed at another point than the one the test is about.
    EXPECT_GE((*session)->totals().acknowledged, n) << "the sender did not reach " << n << " acks in 2 minutes";
  };
  await_acks(kBatches / 4);
  daemon_->Kill();
  daemon_.reset();
  StartDaemon({"--listen", address_});
  await_acks(kBatches / 2);
  StopDaemon();
  StartDaemon({"--listen", address_});
  sender.join();
  ASSERT_TRUE(sent.ok()) << sent;
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_TRUE((*session)->Close(absl::Seconds(120)).ok());

  const auto totals = (*session)->totals();
  EXPECT_EQ(totals.acknowledged, static_cast<uint64_t>(kBatches));
  EXPECT_GE(totals.reconnects, 2u);
  for (uint64_t id = 1; id <= kStates; ++id) {
    auto model = client_->GetStateModel("doors", State::WithId(id));
    ASSERT_TRUE(model.ok() && model->has_value()) << "state " << id;
    EXPECT_EQ((*model)->observations(), static_cast<uint64_t>(kBatches)) << "state " << id;
  }
  auto stats = client_->GetMapStats("doors");
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->observations(), kBatches * kStates);
}

TEST_F(ClientIngestResumeTest, SessionGivesUpAfterItsReconnectTimeout) {
  client::IngestOptions options;
  options.reconnect_timeout = absl::Seconds(2);
  auto session = client_->OpenIngest("doors", options);
  ASSERT_TRUE(session.ok()) << session.status();
  ASSERT_EQ(SendBatches(**session, 0, 3), absl::OkStatus());
  ASSERT_TRUE((*session)->Flush(absl::Seconds(30)).ok());
  daemon_->Kill();
  daemon_.reset();
  ASSERT_EQ(SendBatches(**session, 3, 5), absl::OkStatus());
  absl::Status flushed = (*session)->Flush(absl::Seconds(60));
  EXPECT_EQ(flushed.code(), absl::StatusCode::kUnavailable) << flushed;
  EXPECT_THAT(flushed.message(), ::testing::HasSubstr("gave up reconnecting"));
  EXPECT_THAT(flushed.message(), ::testing::HasSubstr("2 batches not acknowledged"));
  EXPECT_EQ((*session)->unacknowledged(), 2u);
}

}  // namespace
}  // namespace fremen::testing
