// End-to-end tests of the C++ client library (client/lib) against the real fremend: every call of
// Client and IngestSession, the errors it returns (code and the daemon's message), bearer tokens,
// and retries of idempotent calls while the daemon is not up yet.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <future>
#include <thread>

#include "absl/time/clock.h"
#include "client/lib/client.h"
#include "tests/client_daemon_test.h"
#include "tests/delaying_relay.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Cell;
using ::fremen::client::Client;
using ::fremen::client::ConnectionOptions;
using ::fremen::client::IngestAck;
using ::fremen::client::IngestSession;
using ::fremen::client::ScanBuilder;
using ::fremen::client::State;
using ::fremen::client::StateSet;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr double kDay = 86400;
// Midnight UTC.
constexpr double kStart = 1699920000;

v1::Map GridMap(const std::string& name, uint32_t x = 20, uint32_t y = 10) {
  v1::Map map = GridMapSpec(name, x, y, 0.5);
  map.set_shards(1);
  return map;
}

v1::Map GenericMap(const std::string& name) {
  v1::Map map = GenericMapSpec(name);
  map.set_shards(1);
  return map;
}

// 1 (occupied / open) from 8:00 to 18:00, else 0.
float DayPattern(double t) {
  const double hour = std::fmod(t - kStart, kDay) / 3600;
  return hour >= 8 && hour < 18 ? 1.0f : 0.0f;
}

class ClientLibraryTest : public ClientDaemonTest {
 protected:
  void SetUp() override {
    StartDaemon({"--backup-dir", dir_.Path("backups")});
    if (HasFatalFailure()) return;
    ConnectClient();
  }

  void Create(const v1::Map& map) {
    auto created = client_->CreateMap(map);
    ASSERT_TRUE(created.ok()) << created.status();
  }

  // Ingests hourly scans of week `week` of the day pattern into cells (2, 3) and (4, 5) of a grid
  // map (the second inverted), then runs the update job and waits for it.
  void IngestWeekAndUpdate(const std::string& map, int week) {
    auto session = client_->OpenIngest(map);
    ASSERT_TRUE(session.ok()) << session.status();
    for (int hour = 0; hour < 7 * 24; ++hour) {
      const double t = kStart + week * 7 * kDay + hour * 3600.0;
      ScanBuilder scan(t);
      scan.AddCell({2, 3, 0}, DayPattern(t)).AddCell({4, 5, 0}, 1 - DayPattern(t));
      auto built = scan.Build();
      ASSERT_TRUE(built.ok()) << built.status();
      ASSERT_TRUE((*session)->Send(*std::move(built)).ok());
    }
    ASSERT_TRUE((*session)->Close(absl::Seconds(60)).ok());
    EXPECT_EQ((*session)->totals().accepted, 2u * 7 * 24);
    UpdateAndWait(map);
  }

  // Two weeks, each followed by the update: the first update publishes order 0 (no order has been
  // scored yet), the second scores the orders on the second week and picks the daily pattern.
  void IngestTwoWeeks(const std::string& map) {
    IngestWeekAndUpdate(map, 0);
    IngestWeekAndUpdate(map, 1);
  }
};

// --- maps ---

TEST_F(ClientLibraryTest, MapsAreCreatedListedPageByPageAndDeleted) {
  for (const char* name : {"a", "b", "c"}) Create(GridMap(name));
  auto a = client_->GetMap("a");
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ(a->grid().size().x(), 20u);
  EXPECT_EQ(a->max_order(), 5u);  // a default filled in

  auto first = client_->ListMaps(2);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_EQ(first->maps.size(), 2u);
  EXPECT_EQ(first->maps[0].name(), "a");
  ASSERT_FALSE(first->next_page_token.empty());
  auto second = client_->ListMaps(2, first->next_page_token);
  ASSERT_TRUE(second.ok()) << second.status();
  ASSERT_EQ(second->maps.size(), 1u);
  EXPECT_EQ(second->maps[0].name(), "c");
  EXPECT_TRUE(second->next_page_token.empty());
  auto all = client_->ListAllMaps();
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->size(), 3u);

  ASSERT_TRUE(client_->DeleteMap("b").ok());
  auto gone = client_->GetMap("b");
  EXPECT_EQ(gone.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(gone.status().message(), HasSubstr("b"));
  EXPECT_EQ(client_->DeleteMap("b").code(), absl::StatusCode::kNotFound);
}

TEST_F(ClientLibraryTest, MapErrorsCarryTheCodeAndTheDaemonsMessage) {
  Create(GridMap("lab"));
  EXPECT_EQ(client_->CreateMap(GridMap("lab")).status().code(), absl::StatusCode::kAlreadyExists);
  v1::Map bad = GridMap("bad");
  bad.mutable_grid()->set_resolution(-1);
  auto refused = client_->CreateMap(bad);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(refused.status().message(), HasSubstr("resolution"));
  EXPECT_EQ(client_->ListMaps(-1).status().code(), absl::StatusCode::kInvalidArgument);
}

// --- ingest ---

TEST_F(ClientLibraryTest, IngestSessionAcknowledgesScansOfEveryGridKindInOrder) {
  Create(GridMap("lab"));
  std::vector<uint64_t> seen;
  client::IngestOptions options;
  options.writer_id = 77;
  options.first_sequence = 10;
  options.on_ack = [&](const IngestAck& ack) { seen.push_back(ack.sequence); };
  auto session = client_->OpenIngest("lab", options);
  ASSERT_TRUE(session.ok()) << session.status();
  EXPECT_EQ((*session)->writer_id(), 77u);

  ScanBuilder builder(kStart);
  builder.AddCell({0, 0, 0}, 1).AddCell({19, 9, 0}, 0).AddCell({1, 1, 0}, 1.5f).AddCell({25, 0, 0}, 1);
  EXPECT_EQ(*(*session)->Send(*builder.Build()), 10u);
  builder.AddPoint({0.25, 0.25, 0}, 1).AddPoint({100, 0, 0}, 1);
  EXPECT_EQ(*(*session)->Send(*builder.Build()), 11u);
  builder.SetPatch({5, 5, 0}, {2, 2, 1}, {0, 1, 0, 1});
  EXPECT_EQ(*(*session)->Send(*builder.Build()), 12u);
  builder.SetPatchBytes({18, 8, 0}, {4, 4, 1}, std::string(16, '\x80'));  // outside the grid: refused whole
  EXPECT_EQ(*(*session)->Send(*builder.Build()), 13u);
  ASSERT_TRUE((*session)->Flush(absl::Seconds(30)).ok());
  EXPECT_EQ((*session)->unacknowledged(), 0u);

  const std::vector<IngestAck> acks = (*session)->TakeAcks();
  ASSERT_EQ(acks.size(), 4u);
  EXPECT_THAT(seen, ElementsAre(10, 11, 12, 13));
  EXPECT_EQ(acks[0].accepted, 2u);
  EXPECT_EQ(acks[0].rejected, 2u);
  ASSERT_EQ(acks[0].rejections.size(), 2u);
  EXPECT_EQ(acks[0].rejections[0].index, 2u);
  EXPECT_EQ(acks[0].rejections[0].reason, v1::REJECT_REASON_VALUE_OUT_OF_RANGE);
  EXPECT_EQ(acks[0].rejections[1].index, 3u);
  EXPECT_EQ(acks[0].rejections[1].reason, v1::REJECT_REASON_OUTSIDE_MAP);
  EXPECT_EQ(acks[1].accepted, 1u);
  EXPECT_EQ(acks[1].rejected, 1u);
  EXPECT_EQ(acks[2].accepted, 4u);
  EXPECT_EQ(acks[3].error.code(), absl::StatusCode::kOutOfRange) << acks[3].error;
  EXPECT_FALSE(acks[3].error.message().empty());

  const auto totals = (*session)->totals();
  EXPECT_EQ(totals.sent, 4u);
  EXPECT_EQ(totals.acknowledged, 4u);
  EXPECT_EQ(totals.accepted, 7u);
  EXPECT_EQ(totals.rejected, 3u);
  EXPECT_EQ(totals.refused, 1u);
  EXPECT_EQ(totals.reconnects, 0u);
  ASSERT_TRUE((*session)->Close().ok());
  EXPECT_EQ((*session)->Send(*ScanBuilder(kStart).AddCell({0, 0, 0}, 1).Build()).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST_F(ClientLibraryTest, IngestSessionLabelsGenericStatesAndTopStatesRanksThem) {
  Create(GenericMap("doors"));
  auto session = client_->OpenIngest("doors");
  ASSERT_TRUE(session.ok()) << session.status();
  // Door 1 is always open, door 2 never, the named one half the time.
  for (int i = 0; i < 24; ++i) {
    ScanBuilder ids(kStart + i * 3600.0);
    ids.AddState(1, 1, "front", "doors").AddState(2, 0, "back", "doors");
    ASSERT_TRUE((*session)->Send(*ids.Build()).ok());
    ScanBuilder named(kStart + i * 3600.0 + 1);
    named.AddNamedState("side", i % 2, "doors");
    ASSERT_TRUE((*session)->Send(*named.Build()).ok());
  }
  ASSERT_TRUE((*session)->Close(absl::Seconds(30)).ok());
  EXPECT_EQ((*session)->totals().accepted, 3u * 24);

  auto top = client_->TopStates("doors", "doors", kStart + kDay, 3);
  ASSERT_TRUE(top.ok()) << top.status();
  ASSERT_EQ(top->size(), 3u);
  EXPECT_EQ((*top)[0].name(), "front");
  EXPECT_EQ((*top)[2].name(), "back");
  EXPECT_GE((*top)[0].probability(), (*top)[1].probability());
  EXPECT_EQ(client_->TopStates("doors", "windows", kStart, 3).status().code(), absl::StatusCode::kNotFound);

  auto model = client_->GetStateModel("doors", State::Named("side"));
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->has_value());
  EXPECT_EQ((*model)->observations(), 24u);
  EXPECT_EQ((*model)->group(), "doors");
  auto by_id = client_->GetStateModel("doors", State::WithId(1));
  ASSERT_TRUE(by_id.ok() && by_id->has_value());
  EXPECT_EQ((*by_id)->name(), "front");
  auto never = client_->GetStateModel("doors", State::WithId(999));
  ASSERT_TRUE(never.ok()) << never.status();
  EXPECT_FALSE(never->has_value());
}

TEST_F(ClientLibraryTest, AMessageTheDaemonCannotParseEndsTheSessionWithItsPosition) {
  Create(GenericMap("doors"));
  auto session = client_->OpenIngest("doors");
  ASSERT_TRUE(session.ok()) << session.status();
  ASSERT_TRUE((*session)->Send(*ScanBuilder(kStart).AddNamedState("front", 1).Build()).ok());
  ASSERT_TRUE((*session)->Flush(absl::Seconds(30)).ok());
  // Not UTF-8: protobuf sends the string field as it is (logging a complaint), the daemon cannot
  // parse it — as with any message damaged on its way.
  ScanBuilder damaged(kStart + 60);
  damaged.AddNamedState("\xff\xfe", 1);
  (void)(*session)->Send(*damaged.Build());
  const absl::Status flushed = (*session)->Flush(absl::Seconds(30));
  EXPECT_EQ(flushed.code(), absl::StatusCode::kInvalidArgument) << flushed;
  EXPECT_THAT(flushed.message(), HasSubstr("message 2 of the stream: cannot parse IngestRequest"));
  EXPECT_EQ((*session)->unacknowledged(), 1u);
  EXPECT_EQ((*session)->totals().acknowledged, 1u);
  EXPECT_EQ((*session)->Send(*ScanBuilder(kStart + 120).AddNamedState("front", 0).Build()).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_F(ClientLibraryTest, IngestIntoAnUnknownMapFailsAtOpen) {
  auto session = client_->OpenIngest("nowhere");
  EXPECT_EQ(session.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(session.status().message(), HasSubstr("nowhere"));
}

// --- queries ---

TEST_F(ClientLibraryTest, PredictFollowsTheDailyPatternAfterTheUpdate) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  const double noon = kStart + 14 * kDay + 12 * 3600, midnight = kStart + 14 * kDay;
  client::PredictOptions with_states;
  with_states.confidence = 0.5f;
  auto p = client_->Predict("lab", StateSet::Cells({{2, 3, 0}, {4, 5, 0}, {9, 9, 0}}), {noon, midnight}, with_states);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_EQ(p->state_count, 3u);
  EXPECT_EQ(p->time_count, 2u);
  EXPECT_GT(p->probability(0, 0), 0.7f);
  EXPECT_LT(p->probability(1, 0), 0.3f);
  EXPECT_LT(p->probability(0, 1), 0.3f);
  EXPECT_FLOAT_EQ(p->probability(0, 2), 0.5f);
  EXPECT_THAT(p->unobserved, ElementsAre(2u));
  ASSERT_EQ(p->states.size(), 6u);
  EXPECT_TRUE(p->states[0]);
  EXPECT_FALSE(p->states[3]);
  // The same cell by metric point, and at order 0 (the mean: 10 of 24 hours).
  client::PredictOptions order0;
  order0.model.order = 0;
  auto by_point = client_->Predict("lab", StateSet::Points({{1.25, 1.75, 0}}), {noon}, order0);
  ASSERT_TRUE(by_point.ok()) << by_point.status();
  EXPECT_NEAR(by_point->probability(0, 0), 10.0 / 24, 0.02);

  auto bad = client_->Predict("lab", StateSet::Cells({{2, 3, 0}}), {std::nan("")});
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("times"));
}

TEST_F(ClientLibraryTest, RegionIsAssembledFromManyChunksInEveryOutput) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  const double noon = kStart + 14 * kDay + 12 * 3600;
  client::RegionQuery query;
  query.lo = {1, 2, 0};
  query.hi = {6, 7, 1};
  query.time = noon;
  query.chunk_cells = 7;
  auto floats = client_->PredictRegion("lab", query);
  ASSERT_TRUE(floats.ok()) << floats.status();
  EXPECT_EQ(floats->shape, (client::GridShape{5, 5, 1}));
  ASSERT_EQ(floats->floats.size(), 25u);
  auto cells = client_->Predict("lab", StateSet::Cells({{2, 3, 0}, {4, 5, 0}, {1, 2, 0}}), {noon});
  ASSERT_TRUE(cells.ok());
  EXPECT_FLOAT_EQ(floats->floats[floats->Index(1, 1)], cells->probability(0, 0));
  EXPECT_FLOAT_EQ(floats->floats[floats->Index(3, 3)], cells->probability(0, 1));
  EXPECT_FLOAT_EQ(floats->floats[floats->Index(0, 0)], 0.5f);

  query.output = v1::REGION_OUTPUT_UINT8;
  auto bytes = client_->PredictRegion("lab", query);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  EXPECT_EQ(bytes->bytes[bytes->Index(1, 1)], std::lround(255 * cells->probability(0, 0)));
  query.output = v1::REGION_OUTPUT_STATES;
  auto states = client_->PredictRegion("lab", query);
  ASSERT_TRUE(states.ok()) << states.status();
  EXPECT_EQ(states->bytes[states->Index(1, 1)], 1);
  EXPECT_EQ(states->bytes[states->Index(3, 3)], 0);
  query.output = v1::REGION_OUTPUT_ENTROPY;
  auto entropy = client_->PredictRegion("lab", query);
  ASSERT_TRUE(entropy.ok()) << entropy.status();
  EXPECT_FLOAT_EQ(entropy->floats[entropy->Index(0, 0)], 1.0f);  // p = 0.5: one bit

  query.hi = {21, 7, 1};
  auto outside = client_->PredictRegion("lab", query);
  EXPECT_EQ(outside.status().code(), absl::StatusCode::kOutOfRange);
}

// The series as frames: each equals PredictRegion at its time; only the two dynamic cells of the
// box are sent per time.
TEST_F(ClientLibraryTest, RegionSeriesFramesArePredictRegionAtEachTime) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  const double noon = kStart + 14 * kDay + 12 * 3600;
  client::RegionSeriesQuery query;
  query.lo = {1, 2, 0};
  query.hi = {6, 7, 1};
  query.chunk_cells = 7;
  for (int h = 0; h < 24; h += 3) query.times.push_back(noon + h * 3600.0);
  for (const v1::RegionOutput output : {v1::REGION_OUTPUT_FLOAT, v1::REGION_OUTPUT_UINT8}) {
    query.output = output;
    auto series = client_->PredictRegionSeries("lab", query);
    ASSERT_TRUE(series.ok()) << series.status();
    ASSERT_EQ(series->frames.size(), query.times.size());
    EXPECT_EQ(series->varying_cells, 2u);  // (2, 3) and (4, 5)
    EXPECT_EQ(series->values_received, 23u + 2 * query.times.size());
    client::RegionQuery single;
    single.lo = query.lo;
    single.hi = query.hi;
    single.output = output;
    for (size_t t = 0; t < query.times.size(); ++t) {
      single.time = query.times[t];
      auto region = client_->PredictRegion("lab", single);
      ASSERT_TRUE(region.ok()) << region.status();
      EXPECT_EQ(series->frames[t].shape, region->shape);
      EXPECT_EQ(series->frames[t].floats, region->floats) << t;
      EXPECT_EQ(series->frames[t].bytes, region->bytes) << t;
    }
  }
  query.times = {};
  EXPECT_EQ(client_->PredictRegionSeries("lab", query).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(ClientLibraryTest, AnomaliesFlagObservationsAgainstThePattern) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  const double noon = kStart + 14 * kDay + 12 * 3600;
  // At noon (2, 3) is occupied: seeing it free is anomalous, seeing it occupied is not.
  auto anomalies = client_->CheckAnomalies("lab", StateSet::Cells({{2, 3, 0}, {2, 3, 0}}), {0, 1}, {noon}, 0.7f);
  ASSERT_TRUE(anomalies.ok()) << anomalies.status();
  ASSERT_EQ(anomalies->size(), 2u);
  EXPECT_TRUE((*anomalies)[0].anomalous);
  EXPECT_FALSE((*anomalies)[1].anomalous);
  EXPECT_GT((*anomalies)[0].probability, 0.7f);
  auto bad = client_->CheckAnomalies("lab", StateSet::Cells({{2, 3, 0}}), {1}, {noon}, 0.2f);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("confidence"));
}

TEST_F(ClientLibraryTest, StateModelAndMapStatsCountTheObservations) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  auto model = client_->GetStateModel("lab", State::AtCell({2, 3, 0}), /*include_spectrum=*/true);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->has_value());
  EXPECT_EQ((*model)->observations(), 14u * 24);
  EXPECT_NEAR((*model)->mean(), 10.0 / 24, 1e-6);
  EXPECT_EQ((*model)->spectrum_size(), 24);
  EXPECT_GT((*model)->selected_order(), 0u);
  auto stats = client_->GetMapStats("lab");
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->states(), 2u);
  EXPECT_EQ(stats->dynamic_states(), 2u);
  EXPECT_EQ(stats->observations(), 2u * 14 * 24);
  EXPECT_EQ(client_->GetMapStats("nowhere").status().code(), absl::StatusCode::kNotFound);
}

// --- admin ---

TEST_F(ClientLibraryTest, UpdateOperationsAreListedPolledAndCancelled) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  auto page = client_->ListOperations("lab");
  ASSERT_TRUE(page.ok()) << page.status();
  ASSERT_EQ(page->operations.size(), 2u);
  const v1::Operation& op = page->operations[0];  // newest first
  EXPECT_TRUE(op.done());
  EXPECT_EQ(op.update().states_published(), 2u);
  auto got = client_->GetOperation("lab", op.name());
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->name(), op.name());
  // Cancelling an operation that ended answers it unchanged.
  auto cancelled = client_->CancelOperation("lab", op.name());
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  EXPECT_TRUE(cancelled->done());
  EXPECT_EQ(cancelled->error().code(), 0);
  EXPECT_TRUE(client_->ListOperations("", /*running_only=*/true).value().operations.empty());

  // WaitOperation reports progress until done.
  auto again = client_->RunUpdate("lab");
  ASSERT_TRUE(again.ok()) << again.status();
  std::vector<bool> polled;
  client::WaitOptions wait;
  wait.poll_interval = absl::Milliseconds(20);
  wait.on_progress = [&](const v1::Operation& o) { polled.push_back(o.done()); };
  auto done = client_->WaitOperation("lab", again->name(), wait);
  ASSERT_TRUE(done.ok()) << done.status();
  EXPECT_TRUE(done->done());
  ASSERT_FALSE(polled.empty());
  EXPECT_TRUE(polled.back());

  auto unknown = client_->GetOperation("lab", "operations/nope");
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(client_->RunUpdate("nowhere").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(ClientLibraryTest, BackupIsRestoredAsANewMap) {
  Create(GridMap("lab"));
  IngestTwoWeeks("lab");
  auto backup = client_->BackupMap("lab", "nightly/lab", {.timeout = absl::Seconds(120)});
  ASSERT_TRUE(backup.ok()) << backup.status();
  EXPECT_GT(backup->bytes(), 0u);
  EXPECT_TRUE(std::filesystem::exists(backup->path()));
  EXPECT_EQ(client_->BackupMap("lab", "nightly/lab").status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_EQ(client_->BackupMap("lab", "../escape").status().code(), absl::StatusCode::kInvalidArgument);

  auto restored = client_->RestoreMap("nightly/lab", "lab-copy");
  ASSERT_TRUE(restored.ok()) << restored.status();
  EXPECT_EQ(restored->name(), "lab-copy");
  auto stats = client_->GetMapStats("lab-copy");
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->observations(), 2u * 14 * 24);
  EXPECT_EQ(client_->RestoreMap("nightly/lab", "lab").status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_EQ(client_->RestoreMap("no-such-backup", "x").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(ClientLibraryTest, ServerStatusCountsTheMaps) {
  Create(GridMap("lab"));
  Create(GenericMap("doors"));
  auto status = client_->GetServerStatus();
  ASSERT_TRUE(status.ok()) << status.status();
  EXPECT_FALSE(status->version().empty());
  EXPECT_EQ(status->map_count(), 2u);
  EXPECT_EQ(status->store_state(), v1::STORE_STATE_OPEN);
  EXPECT_FALSE(status->tokens_required());
}

// --- connection ---

TEST(ClientConnectionTest, BadOptionsNameTheField) {
  ConnectionOptions options;
  options.address = "";
  EXPECT_THAT(Client::Connect(options).status().message(), HasSubstr("address"));
  options.address = "127.0.0.1:1";
  options.keepalive_time = absl::Seconds(1);
  EXPECT_THAT(Client::Connect(options).status().message(), HasSubstr("keepalive_time"));
  options.keepalive_time = absl::Seconds(20);
  options.connect_timeout = absl::Milliseconds(10);
  EXPECT_THAT(Client::Connect(options).status().message(), HasSubstr("connect_timeout"));
  options.connect_timeout = absl::Seconds(20);
  options.tls_client_cert_pem = "x";
  EXPECT_THAT(Client::Connect(options).status().message(), HasSubstr("tls_client_key_pem"));
}

TEST(ClientConnectionTest, IdempotentCallsRetryUntilTheDaemonComesUp) {
  TempDir dir;
  const std::string address = FreeLoopbackAddress();
  ConnectionOptions options;
  options.address = address;
  options.retry.max_backoff = absl::Milliseconds(200);
  auto client = Client::Connect(options);
  ASSERT_TRUE(client.ok());
  // Nobody listens: a call that is not retried fails at once with UNAVAILABLE naming the address.
  auto refused = client->CreateMap(GridMap("lab"), {.timeout = absl::Seconds(5)});
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(refused.status().message(), HasSubstr(address));

  // The call waits (retrying) in a thread while this one starts the daemon, once the call has
  // failed at least once (a daemon dies with the thread that started it).
  std::promise<void> first_retry;
  std::atomic<int> retries = 0;
  options.retry.on_retry = [&](const absl::Status& failed, absl::Duration) {
    EXPECT_EQ(failed.code(), absl::StatusCode::kUnavailable) << failed;
    if (retries++ == 0) first_retry.set_value();
  };
  auto retrying = Client::Connect(options);
  ASSERT_TRUE(retrying.ok());
  absl::StatusOr<v1::GetServerStatusResponse> status = absl::UnknownError("not called");
  std::thread caller([&] { status = retrying->GetServerStatus({.timeout = absl::Seconds(60)}); });
  const bool retried = first_retry.get_future().wait_for(std::chrono::seconds(60)) == std::future_status::ready;
  auto daemon = FremendProcess::Start(dir.Path("data"), {"--listen", address});
  caller.join();
  ASSERT_TRUE(daemon.ok()) << daemon.status();
  EXPECT_TRUE(retried) << "the call never failed, so it cannot have waited for the daemon";
  EXPECT_TRUE(status.ok()) << status.status();
  EXPECT_GE(retries, 1);
  EXPECT_EQ((*daemon)->Stop(), 0);
}

// A daemon too busy to answer a new connection at once, or a link with a long round trip: the
// attempt waits for the handshake (connect_timeout) instead of being abandoned and made again,
// which, cut shorter than the handshake, would never connect before the backoff grew past it.
TEST(ClientConnectionTest, AHandshakeThatTakesASecondSucceedsAtTheFirstAttempt) {
  TempDir dir;
  auto daemon = FremendProcess::Start(dir.Path("data"));
  ASSERT_TRUE(daemon.ok()) << daemon.status();
  auto relay = DelayingRelay::Start((*daemon)->address(), absl::Seconds(1));
  ASSERT_TRUE(relay.ok()) << relay.status();
  ConnectionOptions options;
  options.address = (*relay)->address();
  auto client = Client::Connect(options);
  ASSERT_TRUE(client.ok());
  auto status = client->GetServerStatus({.timeout = absl::Seconds(60)});
  EXPECT_TRUE(status.ok()) << status.status();
  EXPECT_EQ((*relay)->accepted(), 1) << "connection attempts were abandoned before the handshake could finish";
}

TEST(ClientConnectionTest, TlsWithTheDaemonsRootCertificate) {
  TempDir dir;
  const std::optional<TestCertificate> certificate = MakeTestCertificate(dir);
  if (!certificate) GTEST_SKIP() << "openssl cannot make a test certificate";
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = certificate->cert_pem;
  auto daemon = FremendProcess::Start(
      dir.Path("data"), {"--tls-cert-file", certificate->cert_path, "--tls-key-file", certificate->key_path},
      grpc::SslCredentials(ssl));
  ASSERT_TRUE(daemon.ok()) << daemon.status();
  ConnectionOptions options;
  options.address = (*daemon)->address();
  options.tls_root_certs_pem = certificate->cert_pem;
  auto status = Client::Connect(options)->GetServerStatus();
  ASSERT_TRUE(status.ok()) << status.status();
  EXPECT_TRUE(status->tls());
  // Without TLS the daemon is not reachable: the handshake fails.
  options.tls_root_certs_pem.clear();
  options.retry.max_attempts = 1;
  EXPECT_EQ(Client::Connect(options)->GetServerStatus({.timeout = absl::Seconds(5)}).status().code(),
            absl::StatusCode::kUnavailable);
  EXPECT_EQ((*daemon)->Stop(), 0);
}

class ClientTokenTest : public DaemonTest {
 protected:
  void SetUp() override { StartDaemon({"--tokens", "read:reader-token write:writer-token"}); }
  Client As(const std::string& token) {
    ConnectionOptions options;
    options.address = daemon_->address();
    options.token = token;
    return *Client::Connect(options);
  }
};

TEST_F(ClientTokenTest, TokensAreSentAsBearerMetadata) {
  ASSERT_TRUE(As("writer-token").CreateMap(GridMap("lab")).ok());
  EXPECT_TRUE(As("reader-token").GetMap("lab").ok());
  auto anonymous = As("").GetMap("lab");
  EXPECT_EQ(anonymous.status().code(), absl::StatusCode::kUnauthenticated);
  EXPECT_THAT(anonymous.status().message(), HasSubstr("Bearer"));
  EXPECT_EQ(As("wrong").GetMap("lab").status().code(), absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(As("reader-token").DeleteMap("lab").code(), absl::StatusCode::kPermissionDenied);
}

TEST_F(ClientTokenTest, IngestWithAReadTokenEndsTheSessionWithPermissionDenied) {
  ASSERT_TRUE(As("writer-token").CreateMap(GridMap("lab")).ok());
  Client reader = As("reader-token");
  auto session = reader.OpenIngest("lab");
  ASSERT_TRUE(session.ok()) << session.status();
  ASSERT_TRUE((*session)->Send(*ScanBuilder(kStart).AddCell({0, 0, 0}, 1).Build()).ok());
  absl::Status flushed = (*session)->Flush(absl::Seconds(30));
  EXPECT_EQ(flushed.code(), absl::StatusCode::kPermissionDenied) << flushed;
  EXPECT_THAT(flushed.message(), HasSubstr("write token"));
  EXPECT_EQ((*session)->unacknowledged(), 1u);
  EXPECT_EQ((*session)->Send(*ScanBuilder(kStart).AddCell({0, 0, 0}, 1).Build()).status().code(),
            absl::StatusCode::kPermissionDenied);
}

}  // namespace
}  // namespace fremen::testing
