// End-to-end tests of a map's export and import (AdminService.ExportMap / ImportMap) and of the
// move steps (SetMapMove) against real fremend processes (docs/fleet.md, "Moving a map"): an
// exported map imported on another daemon answers exactly as the original — predictions, stats, a
// state's model, the lossless history, the writers' deduplication windows — a damaged or torn
// stream is DATA_LOSS and leaves nothing, an existing name is ALREADY_EXISTS, a read token may do
// neither; while a map's writes are stopped its writers get the retryable UNAVAILABLE and its
// queries answer, and a committed move survives a restart; `fremenctl export`/`import` round-trip
// a file.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/lib/client.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::fremen::client::Client;
using ::fremen::client::ConnectionOptions;
using ::fremen::client::IngestOptions;
using ::fremen::client::IngestTotals;
using ::fremen::client::ScanBuilder;
using ::testing::HasSubstr;

constexpr double kT0 = 1'700'006'400;  // a Monday 00:00 UTC
constexpr double kDelta = 600;         // the lossless map's slots
constexpr int kSlots = 3 * 144;        // three days of them
constexpr uint32_t kNx = 4, kNy = 3;
constexpr uint64_t kWriter = 77;

// A door that opens by day, with a few stray slots.
bool Open(int slot, uint32_t cell) { return ((slot % 144) >= 48 && (slot % 144) < 120) != ((slot + cell) % 97 == 5); }

class MapTransferTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < 2; ++i) {
      auto process = FremendProcess::Start(dir_.Path(absl::StrCat("daemon-", i)), args_);
      ASSERT_TRUE(process.ok()) << process.status();
      daemons_.push_back(*std::move(process));
    }
  }

  Client ClientOf(int daemon, const std::string& token = "") const {
    ConnectionOptions options;
    options.address = daemons_[daemon]->address();
    options.token = token;
    options.retry.max_attempts = 1;
    return *Client::Connect(options);
  }

  // A lossless grid written by writer kWriter, sequences 1..kSlots, then updated.
  void MakeHall(const Client& client) {
    v1::Map spec = GridMapSpec("hall", kNx, kNy, 0.5);
    spec.set_lossless_sampling_seconds(kDelta);
    spec.set_lossless_origin(kT0);
    spec.set_shards(2);
    ASSERT_TRUE(client.CreateMap(spec).ok());
    IngestOptions options;
    options.writer_id = kWriter;
    auto session = client.OpenIngest("hall", options);
    ASSERT_TRUE(session.ok()) << session.status();
    for (int i = 0; i < kSlots; ++i) {
      ScanBuilder scan(kT0 + kDelta * i);
      for (uint32_t y = 0; y < kNy; ++y) {
        for (uint32_t x = 0; x < kNx; ++x) scan.AddCell({x, y, 0}, Open(i, x + kNx * y));
      }
      ASSERT_TRUE((*session)->Send(*scan.Build()).ok());
    }
    ASSERT_TRUE((*session)->Close().ok());
    auto op = client.RunUpdate("hall");
    ASSERT_TRUE(op.ok()) << op.status();
    auto done = client.WaitOperation("hall", op->name());
    ASSERT_TRUE(done.ok() && done->error().code() == 0) << done.status();
  }

  static std::vector<v1::MapChunk> Export(const Client& client, const std::string& map, uint32_t chunk_bytes = 0) {
    std::vector<v1::MapChunk> chunks;
    const absl::Status status = client.ExportMap(
        map,
        [&](const v1::MapChunk& chunk) {
          chunks.push_back(chunk);
          return absl::OkStatus();
        },
        {}, chunk_bytes);
    EXPECT_TRUE(status.ok()) << status;
    return chunks;
  }

  static absl::StatusOr<v1::ImportMapResponse> Import(const Client& client, const std::string& map,
                                                      const std::vector<v1::MapChunk>& chunks) {
    size_t next = 0;
    return client.ImportMap(map, [&](v1::MapChunk& chunk) -> absl::StatusOr<bool> {
      if (next == chunks.size()) return false;
      chunk = chunks[next++];
      return true;
    });
  }

  std::vector<std::string> MapNames(int daemon) const {
    auto maps = ClientOf(daemon).ListAllMaps();
    EXPECT_TRUE(maps.ok()) << maps.status();
    std::vector<std::string> names;
    if (maps.ok()) {
      for (const v1::Map& m : *maps) names.push_back(m.name());
    }
    return names;
  }

  // Nothing staged is left in the daemon's data directory.
  void ExpectNothingStaged(int daemon) const {
    const std::string transfers = dir_.Path(absl::StrCat("daemon-", daemon, "/transfers"));
    if (!std::filesystem::exists(transfers)) return;
    EXPECT_TRUE(std::filesystem::is_empty(transfers)) << transfers;
  }

  std::vector<std::string> args_;
  TempDir dir_;
  std::vector<std::unique_ptr<FremendProcess>> daemons_;
};

v1::ReconstructResponse Reconstruct(const FremendProcess& daemon, const std::string& map) {
  auto query = v1::QueryService::NewStub(daemon.NewChannel());
  v1::ReconstructRequest request;
  request.set_map(map);
  *request.mutable_states() = PlaneCells(kNx, kNy);
  request.set_start_time(kT0);
  request.set_end_time(kT0 + kDelta * kSlots);
  v1::ReconstructResponse response;
  const grpc::Status status = query->Reconstruct(CallContext().get(), request, &response);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return response;
}

// Writer kWriter's last batch of the hall (sequence kSlots) sent again: a duplicate wherever the
// writer's window is the hall's.
IngestTotals ResendLastHallBatch(const Client& client) {
  IngestOptions options;
  options.writer_id = kWriter;
  options.first_sequence = kSlots;
  auto session = client.OpenIngest("hall", options);
  EXPECT_TRUE(session.ok()) << session.status();
  if (!session.ok()) return {};
  ScanBuilder last(kT0 + kDelta * (kSlots - 1));
  for (uint32_t y = 0; y < kNy; ++y) {
    for (uint32_t x = 0; x < kNx; ++x) last.AddCell({x, y, 0}, Open(kSlots - 1, x + kNx * y));
  }
  EXPECT_TRUE((*session)->Send(*last.Build()).ok());
  EXPECT_TRUE((*session)->Close().ok());
  return (*session)->totals();
}

TEST_F(MapTransferTest, AnImportedMapAnswersExactlyAsTheExportedOne) {
  const Client a = ClientOf(0), b = ClientOf(1);
  MakeHall(a);
  if (HasFatalFailure()) return;
  // Small chunks, so that each shard's file is many of them.
  const std::vector<v1::MapChunk> chunks = Export(a, "hall", 4096);
  ASSERT_GT(chunks.size(), 4u);
  ASSERT_TRUE(chunks.front().has_header());
  EXPECT_EQ(chunks.front().header().map(), "hall");
  EXPECT_EQ(chunks.front().header().files_size(), 2);
  ASSERT_TRUE(chunks.back().has_trailer());
  EXPECT_EQ(chunks.back().trailer().chunks(), chunks.size() - 2);
  auto imported = Import(b, "hall", chunks);
  ASSERT_TRUE(imported.ok()) << imported.status();
  EXPECT_EQ(imported->map().name(), "hall");
  EXPECT_EQ(imported->map().lossless_sampling_seconds(), kDelta);
  EXPECT_GT(imported->bytes(), 0u);

  auto before = a.GetMapStats("hall"), after = b.GetMapStats("hall");
  ASSERT_TRUE(before.ok() && after.ok());
  EXPECT_EQ(after->observations(), before->observations());
  EXPECT_EQ(after->observations(), static_cast<uint64_t>(kSlots) * kNx * kNy);
  EXPECT_EQ(after->states(), before->states());
  EXPECT_EQ(after->dynamic_states(), before->dynamic_states());
  ASSERT_TRUE(after->has_last_update()) << "the last update job's record comes along";
  EXPECT_EQ(after->last_update().states_updated(), before->last_update().states_updated());

  std::vector<double> times;
  for (int h = 0; h < 48; ++h) times.push_back(kT0 + kSlots * kDelta + 3600.0 * h);
  std::vector<client::Cell> every;
  for (uint32_t y = 0; y < kNy; ++y) {
    for (uint32_t x = 0; x < kNx; ++x) every.push_back({x, y, 0});
  }
  const auto cells = client::StateSet::Cells(every);
  auto p_a = a.Predict("hall", cells, times), p_b = b.Predict("hall", cells, times);
  ASSERT_TRUE(p_a.ok() && p_b.ok()) << p_a.status() << p_b.status();
  EXPECT_EQ(p_b->probabilities, p_a->probabilities);

  v1::StateRef door;
  door.mutable_cell()->set_x(2);
  door.mutable_cell()->set_y(1);
  auto m_a = a.GetStateModel("hall", door, true), m_b = b.GetStateModel("hall", door, true);
  ASSERT_TRUE(m_a.ok() && m_b.ok() && m_a->has_value() && m_b->has_value());
  EXPECT_EQ((*m_b)->SerializeAsString(), (*m_a)->SerializeAsString());

  const v1::ReconstructResponse r_a = Reconstruct(*daemons_[0], "hall"), r_b = Reconstruct(*daemons_[1], "hall");
  ASSERT_EQ(r_b.histories_size(), static_cast<int>(kNx * kNy));
  for (int s = 0; s < r_b.histories_size(); ++s) {
    EXPECT_EQ(r_b.histories(s).slots(), r_a.histories(s).slots()) << "state " << s;
    for (int i = 0; i < kSlots; ++i) ASSERT_EQ(r_b.histories(s).slots()[i], Open(i, s) ? 1 : 0) << "slot " << i;
  }

  // The writer's window came along: where to continue, and a resent batch is a duplicate.
  EXPECT_EQ(ResendLastHallBatch(b).duplicates, 1u);
  EXPECT_EQ(b.GetMapStats("hall")->observations(), after->observations());
  ExpectNothingStaged(0);
  ExpectNothingStaged(1);
}

TEST_F(MapTransferTest, ADamagedOrTornStreamIsDataLossAndLeavesNothing) {
  const Client a = ClientOf(0), b = ClientOf(1);
  MakeHall(a);
  if (HasFatalFailure()) return;
  const std::vector<v1::MapChunk> chunks = Export(a, "hall", 4096);
  ASSERT_GT(chunks.size(), 4u);

  std::vector<v1::MapChunk> flipped = chunks;
  std::string& bytes = *flipped[2].mutable_data()->mutable_data();
  bytes[bytes.size() / 2] ^= 0x10;
  auto damaged = Import(b, "hall", flipped);
  EXPECT_EQ(damaged.status().code(), absl::StatusCode::kDataLoss) << damaged.status();
  EXPECT_THAT(damaged.status().message(), HasSubstr("checksum mismatch"));

  std::vector<v1::MapChunk> torn(chunks.begin(), chunks.end() - 3);  // cut before the trailer
  auto cut = Import(b, "hall", torn);
  EXPECT_EQ(cut.status().code(), absl::StatusCode::kDataLoss) << cut.status();
  EXPECT_THAT(cut.status().message(), HasSubstr("before its trailer"));

  std::vector<v1::MapChunk> skipped = chunks;
  skipped.erase(skipped.begin() + 2);  // a chunk lost on the way
  auto missing = Import(b, "hall", skipped);
  EXPECT_EQ(missing.status().code(), absl::StatusCode::kDataLoss) << missing.status();

  std::vector<v1::MapChunk> headless(chunks.begin() + 1, chunks.end());
  EXPECT_EQ(Import(b, "hall", headless).status().code(), absl::StatusCode::kDataLoss);

  EXPECT_TRUE(MapNames(1).empty());
  ExpectNothingStaged(1);
  // The intact stream still imports.
  EXPECT_TRUE(Import(b, "hall", chunks).ok());
}

TEST_F(MapTransferTest, AnExistingNameIsAlreadyExistsAndAnUnknownMapNotFound) {
  const Client a = ClientOf(0);
  MakeHall(a);
  if (HasFatalFailure()) return;
  const std::vector<v1::MapChunk> chunks = Export(a, "hall");
  auto again = Import(a, "hall", chunks);
  EXPECT_EQ(again.status().code(), absl::StatusCode::kAlreadyExists) << again.status();
  std::vector<v1::MapChunk> renamed = chunks;
  renamed[0].mutable_header()->set_map("hall-2");
  auto copy = Import(a, "hall-2", renamed);
  ASSERT_TRUE(copy.ok()) << copy.status();
  EXPECT_EQ(a.GetMapStats("hall-2")->observations(), a.GetMapStats("hall")->observations());
  // The header and x-fremen-map must agree, as for every call.
  EXPECT_EQ(Import(a, "other", chunks).status().code(), absl::StatusCode::kInvalidArgument);
  const absl::Status unknown = a.ExportMap("nothing", [](const v1::MapChunk&) { return absl::OkStatus(); });
  EXPECT_EQ(unknown.code(), absl::StatusCode::kNotFound) << unknown;
  ExpectNothingStaged(0);
}

TEST_F(MapTransferTest, StoppedWritesAreRetryableQueriesGoOnAndAMoveIsKeptAcrossARestart) {
  const Client a = ClientOf(0);
  MakeHall(a);
  if (HasFatalFailure()) return;
  auto stopped = a.SetMapMove("hall", v1::MAP_MOVE_STEP_STOP_WRITES);
  ASSERT_TRUE(stopped.ok()) << stopped.status();
  EXPECT_EQ(stopped->state(), v1::MAP_MOVE_STATE_WRITES_STOPPED);
  EXPECT_EQ(a.GetMap("hall")->move_state(), v1::MAP_MOVE_STATE_WRITES_STOPPED);

  const auto write_once = [&] {
    IngestOptions options;
    options.reconnect_timeout = absl::ZeroDuration();
    auto session = a.OpenIngest("hall", options);
    if (!session.ok()) return session.status();
    (void)(*session)->Send(*ScanBuilder(kT0 + kDelta * kSlots).AddCell({0, 0, 0}, 1).Build());
    return (*session)->Close();
  };
  const absl::Status refused = write_once();
  EXPECT_EQ(refused.code(), absl::StatusCode::kUnavailable) << refused;
  EXPECT_THAT(refused.message(), HasSubstr("map hall is moving to another daemon; retry"));
  const absl::Status update = a.RunUpdate("hall").status();
  EXPECT_EQ(update.code(), absl::StatusCode::kUnavailable) << update;
  EXPECT_THAT(update.message(), HasSubstr("is moving to another daemon"));
  EXPECT_TRUE(a.GetMapStats("hall").ok());
  EXPECT_TRUE(a.Predict("hall", client::StateSet::Cells({{1, 1}}), {kT0}).ok());

  // Given up: writes again.
  ASSERT_TRUE(a.SetMapMove("hall", v1::MAP_MOVE_STEP_RESUME_WRITES).ok());
  EXPECT_TRUE(write_once().ok());
  // Committed: refused for good, across a restart; only deleting the copy ends it.
  ASSERT_TRUE(a.SetMapMove("hall", v1::MAP_MOVE_STEP_MOVED, "elsewhere:1").status().code() ==
              absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE(a.SetMapMove("hall", v1::MAP_MOVE_STEP_STOP_WRITES).ok());
  auto moved = a.SetMapMove("hall", v1::MAP_MOVE_STEP_MOVED, "elsewhere:1");
  ASSERT_TRUE(moved.ok()) << moved.status();
  EXPECT_EQ(moved->state(), v1::MAP_MOVE_STATE_MOVED);
  EXPECT_EQ(a.SetMapMove("hall", v1::MAP_MOVE_STEP_RESUME_WRITES).status().code(),
            absl::StatusCode::kFailedPrecondition);
  ASSERT_EQ(daemons_[0]->Stop(), 0);
  auto restarted = FremendProcess::Start(dir_.Path("daemon-0"), {"--listen", daemons_[0]->address()});
  ASSERT_TRUE(restarted.ok()) << restarted.status();
  daemons_[0] = *std::move(restarted);
  const Client again = ClientOf(0);
  auto map = again.GetMap("hall");
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_EQ(map->move_state(), v1::MAP_MOVE_STATE_MOVED);
  EXPECT_EQ(map->moved_to(), "elsewhere:1");
  EXPECT_EQ(write_once().code(), absl::StatusCode::kUnavailable);
  EXPECT_TRUE(again.GetMapStats("hall").ok());
  ASSERT_TRUE(again.DeleteMap("hall").ok());
}

class MapTransferTokenTest : public MapTransferTest {
 protected:
  void SetUp() override {
    args_ = {"--tokens-file", dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n")};
    MapTransferTest::SetUp();
  }
};

TEST_F(MapTransferTokenTest, AReadTokenMayNeitherExportNorImportNorMove) {
  const Client writer = ClientOf(0, "writer-token"), reader = ClientOf(0, "reader-token");
  ASSERT_TRUE(writer.CreateMap(GenericMapSpec("lab")).ok());
  const absl::Status exported = reader.ExportMap("lab", [](const v1::MapChunk&) { return absl::OkStatus(); });
  EXPECT_EQ(exported.code(), absl::StatusCode::kPermissionDenied) << exported;
  EXPECT_THAT(exported.message(), HasSubstr("ExportMap"));
  std::vector<v1::MapChunk> chunks = Export(writer, "lab");
  chunks[0].mutable_header()->set_map("lab-copy");
  auto imported = Import(reader, "lab-copy", chunks);
  EXPECT_EQ(imported.status().code(), absl::StatusCode::kPermissionDenied) << imported.status();
  EXPECT_EQ(reader.SetMapMove("lab", v1::MAP_MOVE_STEP_STOP_WRITES).status().code(),
            absl::StatusCode::kPermissionDenied);
  EXPECT_TRUE(Import(writer, "lab-copy", chunks).ok());
}

// LastSequence asked of one daemon directly: where the writer continues, or the refusal of a map
// that takes no writes.
absl::StatusOr<uint64_t> LastSequenceOn(const FremendProcess& daemon, const std::string& map, uint64_t writer) {
  auto ingest = v1::IngestService::NewStub(daemon.NewChannel());
  v1::LastSequenceRequest request;
  request.set_map(map);
  request.set_writer_id(writer);
  v1::LastSequenceResponse response;
  const grpc::Status status = ingest->LastSequence(CallContext().get(), request, &response);
  if (!status.ok()) return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
  return response.last_sequence();
}

// Sends `count` one-cell batches as writer `writer`, each after the hall's slots: the same batches
// every time, under sequences from 1 when first_sequence is 1 (a resend), else after the writer's
// last one.
IngestTotals WriteMore(const Client& client, uint64_t writer, int count, uint64_t first_sequence = 0) {
  IngestOptions options;
  options.writer_id = writer;
  options.first_sequence = first_sequence;
  options.reconnect_timeout = absl::ZeroDuration();
  auto session = client.OpenIngest("hall", options);
  EXPECT_TRUE(session.ok()) << session.status();
  if (!session.ok()) return {};
  for (int i = 0; i < count; ++i) {
    const uint32_t cell = static_cast<uint32_t>(i) % kNx;
    EXPECT_TRUE((*session)->Send(*ScanBuilder(kT0 + kDelta * (kSlots + i)).AddCell({cell, 1, 0}, i % 2).Build()).ok());
  }
  EXPECT_TRUE((*session)->Close().ok());
  return (*session)->totals();
}

TEST_F(MapTransferTest, AnOnlineCopyTakesWritesDuringItsSnapshotAndItsTailCarriesThemExactly) {
  const Client a = ClientOf(0);
  MakeHall(a);
  if (HasFatalFailure()) return;
  auto snapshot = a.CopyMapTo(ClientOf(1), "hall", "", {}, v1::MAP_EXPORT_KIND_ONLINE_SNAPSHOT);
  ASSERT_TRUE(snapshot.ok()) << snapshot.status();
  EXPECT_GT(snapshot->snapshot_lsn(), 0u);
  EXPECT_EQ(snapshot->map().move_state(), v1::MAP_MOVE_STATE_INCOMING);
  EXPECT_EQ(a.GetMap("hall")->move_state(), v1::MAP_MOVE_STATE_COPYING);
  const uint64_t in_snapshot = ClientOf(1).GetMapStats("hall")->observations();
  EXPECT_EQ(in_snapshot, static_cast<uint64_t>(kSlots) * kNx * kNy);

  // The source takes writes meanwhile, acknowledged as usual: a second writer's, and a resend of
  // the first writer's last batch (a duplicate: not applied, and not in the tail).
  constexpr int kMore = 25;
  const IngestTotals more = WriteMore(a, kWriter + 1, kMore);
  EXPECT_EQ(more.acknowledged, static_cast<uint64_t>(kMore));
  EXPECT_EQ(more.duplicates, 0u);
  EXPECT_EQ(ResendLastHallBatch(a).duplicates, 1u);
  // The update job is refused while the map is copied (its publication cannot ride in a tail).
  EXPECT_EQ(a.RunUpdate("hall").status().code(), absl::StatusCode::kUnavailable);
  // The copy refuses writes, retryably, until its tail is applied — also after a kill -9.
  EXPECT_EQ(LastSequenceOn(*daemons_[1], "hall", kWriter).status().code(), absl::StatusCode::kUnavailable);
  daemons_[1]->Kill();
  auto restarted = FremendProcess::Start(dir_.Path("daemon-1"), args_);
  ASSERT_TRUE(restarted.ok()) << restarted.status();
  daemons_[1] = *std::move(restarted);
  const Client b = ClientOf(1);
  EXPECT_EQ(b.GetMap("hall")->move_state(), v1::MAP_MOVE_STATE_INCOMING);
  EXPECT_EQ(LastSequenceOn(*daemons_[1], "hall", kWriter).status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(b.GetMapStats("hall")->observations(), in_snapshot);

  ASSERT_TRUE(a.SetMapMove("hall", v1::MAP_MOVE_STEP_STOP_WRITES).ok());
  const uint64_t at_source = a.GetMapStats("hall")->observations();
  EXPECT_EQ(at_source, in_snapshot + kMore);
  auto tail = a.CopyMapTo(b, "hall", "", {}, v1::MAP_EXPORT_KIND_TAIL, snapshot->snapshot_lsn());
  ASSERT_TRUE(tail.ok()) << tail.status();
  EXPECT_EQ(tail->tail_batches(), static_cast<uint64_t>(kMore));
  EXPECT_EQ(tail->map().move_state(), v1::MAP_MOVE_STATE_SERVING);
  EXPECT_EQ(b.GetMapStats("hall")->observations(), at_source);
  // The writers' windows are the source's: where each continues, and a resend is a duplicate.
  EXPECT_EQ(LastSequenceOn(*daemons_[1], "hall", kWriter).value_or(0), static_cast<uint64_t>(kSlots));
  EXPECT_EQ(LastSequenceOn(*daemons_[1], "hall", kWriter + 1).value_or(0), static_cast<uint64_t>(kMore));
  const IngestTotals again = WriteMore(b, kWriter + 1, kMore, /*first_sequence=*/1);  // the tail's batches resent
  EXPECT_EQ(again.acknowledged, static_cast<uint64_t>(kMore));
  EXPECT_EQ(again.duplicates, static_cast<uint64_t>(kMore));
  EXPECT_EQ(b.GetMapStats("hall")->observations(), at_source);
  ExpectNothingStaged(0);
  ExpectNothingStaged(1);
}

TEST_F(MapTransferTest, ADamagedTailIsDataLossAndLeavesTheTargetWithoutTheMap) {
  const Client a = ClientOf(0), b = ClientOf(1);
  MakeHall(a);
  if (HasFatalFailure()) return;
  // A snapshot copied online, three batches after it, writes stopped: the tail to send.
  const auto snapshot_and_tail = [&](std::vector<v1::MapChunk>& tail) -> uint64_t {
    auto resumed = a.SetMapMove("hall", v1::MAP_MOVE_STEP_RESUME_WRITES);
    EXPECT_TRUE(resumed.ok()) << resumed.status();
    auto snapshot = a.CopyMapTo(b, "hall", "", {}, v1::MAP_EXPORT_KIND_ONLINE_SNAPSHOT);
    EXPECT_TRUE(snapshot.ok()) << snapshot.status();
    if (!snapshot.ok()) return 0;
    WriteMore(a, kWriter + 1 + snapshot->snapshot_lsn(), 3);
    EXPECT_TRUE(a.SetMapMove("hall", v1::MAP_MOVE_STEP_STOP_WRITES).ok());
    tail.clear();
    const absl::Status exported = a.ExportMap(
        "hall",
        [&](const v1::MapChunk& chunk) {
          tail.push_back(chunk);
          return absl::OkStatus();
        },
        {}, 0, v1::MAP_EXPORT_KIND_TAIL, snapshot->snapshot_lsn());
    EXPECT_TRUE(exported.ok()) << exported;
    return snapshot->snapshot_lsn();
  };
  std::vector<v1::MapChunk> tail;
  snapshot_and_tail(tail);
  ASSERT_EQ(tail.size(), 5u) << "header, three batches, trailer";
  ASSERT_TRUE(tail[2].has_batch());
  std::string& bytes = *tail[2].mutable_batch()->mutable_batch();
  bytes[bytes.size() / 2] ^= 0x10;
  auto damaged = Import(b, "hall", tail);
  EXPECT_EQ(damaged.status().code(), absl::StatusCode::kDataLoss) << damaged.status();
  EXPECT_THAT(damaged.status().message(), HasSubstr("checksum mismatch"));
  EXPECT_TRUE(MapNames(1).empty()) << "the incoming copy is deleted with its damaged tail";

  snapshot_and_tail(tail);
  tail.erase(tail.begin() + 2);  // a batch lost on the way
  auto skipped = Import(b, "hall", tail);
  EXPECT_EQ(skipped.status().code(), absl::StatusCode::kDataLoss) << skipped.status();
  EXPECT_TRUE(MapNames(1).empty());

  snapshot_and_tail(tail);
  tail.pop_back();  // torn before the trailer
  auto torn = Import(b, "hall", tail);
  EXPECT_EQ(torn.status().code(), absl::StatusCode::kDataLoss) << torn.status();
  EXPECT_THAT(torn.status().message(), HasSubstr("before its trailer"));
  EXPECT_TRUE(MapNames(1).empty());

  // A tail of another snapshot does not continue this one.
  const uint64_t lsn = snapshot_and_tail(tail);
  tail[0].mutable_header()->set_snapshot_lsn(lsn - 1);
  auto other = Import(b, "hall", tail);
  EXPECT_EQ(other.status().code(), absl::StatusCode::kFailedPrecondition) << other.status();
  EXPECT_TRUE(MapNames(1).empty());
  ExpectNothingStaged(1);

  // The intact tail of a fresh snapshot makes the copy serve, equal to the source.
  snapshot_and_tail(tail);
  auto applied = Import(b, "hall", tail);
  ASSERT_TRUE(applied.ok()) << applied.status();
  EXPECT_EQ(applied->tail_batches(), 3u);
  EXPECT_EQ(b.GetMapStats("hall")->observations(), a.GetMapStats("hall")->observations());
  EXPECT_EQ(b.GetMap("hall")->move_state(), v1::MAP_MOVE_STATE_SERVING);
}

TEST_F(MapTransferTest, FremenctlExportAndImportRoundTripAFile) {
  const Client a = ClientOf(0), b = ClientOf(1);
  MakeHall(a);
  if (HasFatalFailure()) return;
  const std::string file = dir_.Path("hall.fremen");
  const RunResult exported = RunProgram(FREMENCTL_BINARY, {"export", "--map", "hall", "--out", file, "--address",
                                                           daemons_[0]->address()});
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_THAT(exported.out, HasSubstr("exported map hall to"));
  const RunResult imported = RunProgram(FREMENCTL_BINARY, {"import", "--in", file, "--map", "hall-copy",
                                                           "--address", daemons_[1]->address()});
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  EXPECT_THAT(imported.out, HasSubstr("imported map hall-copy"));
  EXPECT_EQ(b.GetMapStats("hall-copy")->observations(), a.GetMapStats("hall")->observations());
  const RunResult again = RunProgram(FREMENCTL_BINARY, {"import", "--in", file, "--map", "hall-copy",
                                                        "--address", daemons_[1]->address()});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.err, HasSubstr("already exists"));
  const RunResult not_an_export = RunProgram(FREMENCTL_BINARY, {"import", "--in", dir_.Write("x", "hello"),
                                                                "--address", daemons_[1]->address()});
  EXPECT_EQ(not_an_export.exit_code, 1);
  EXPECT_THAT(not_an_export.err, HasSubstr("is not a file written by `fremenctl export`"));
}

}  // namespace
}  // namespace fremen::testing
