// End-to-end tests of the compact scan encoding (ingest.proto CompactCells) against the real
// fremend: a map fed compact scans holds bit-identical models to one fed the same scans as
// CellObservations, also after kill -9 and recovery from the log; malformed bytes refuse the batch
// with INVALID_ARGUMENT naming the field while the stream goes on; cells past the grid are
// rejected one by one as outside the map.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "base/compact_scan.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

constexpr double kTime = 1.7e9;
constexpr uint32_t kNx = 16, kNy = 8, kNz = 2;  // 256 cells

v1::Map Grid(const std::string& name) {
  v1::Map map = GridMapSpec(name, kNx, kNy, 0.5);
  map.mutable_grid()->mutable_size()->set_z(kNz);
  map.set_shards(2);
  return map;
}

// A scan: sorted linear indices and their values (soft ones multiples of 1/255, which both
// encodings carry exactly).
struct TestScan {
  std::vector<uint64_t> indices;
  std::vector<float> values;
  bool soft = false;
};

TestScan RandomScan(std::mt19937_64& random, bool soft) {
  TestScan scan;
  scan.soft = soft;
  for (uint64_t i = 0; i < kNx * kNy * kNz; ++i) {
    if (random() % 3 == 0) continue;
    scan.indices.push_back(i);
    scan.values.push_back(soft ? static_cast<float>(random() % 256) / 255.0f : static_cast<float>(random() % 2));
  }
  return scan;
}

v1::IngestRequest Header(const std::string& map, uint64_t sequence) {
  v1::IngestRequest request;
  request.set_map(map);
  request.set_writer_id(3);
  request.set_sequence(sequence);
  request.set_time(kTime + 60.0 * static_cast<double>(sequence));
  return request;
}

v1::IngestRequest AsCells(const std::string& map, uint64_t sequence, const TestScan& scan) {
  v1::IngestRequest request = Header(map, sequence);
  v1::CellIndices& cells = *request.mutable_cells()->mutable_cells();
  for (uint64_t i : scan.indices) {
    cells.add_x(static_cast<uint32_t>(i % kNx));
    cells.add_y(static_cast<uint32_t>(i / kNx % kNy));
    cells.add_z(static_cast<uint32_t>(i / (kNx * kNy)));
  }
  for (float v : scan.values) request.mutable_cells()->add_values(v);
  return request;
}

v1::IngestRequest AsCompact(const std::string& map, uint64_t sequence, const TestScan& scan) {
  v1::IngestRequest request = Header(map, sequence);
  v1::CompactCells& compact = *request.mutable_compact();
  compact.set_indices(EncodeIndexGaps(scan.indices));
  if (scan.soft) {
    std::string bytes;
    for (float v : scan.values) bytes.push_back(static_cast<char>(static_cast<uint8_t>(v * 255.0f + 0.5f)));
    compact.set_probabilities(bytes);
  } else {
    compact.set_occupied(PackOccupiedBits(scan.values));
  }
  return request;
}

class CompactIngestTest : public DaemonTest {
 protected:
  // The stubs on a channel to the daemon running now (again after a restart).
  struct Stubs {
    explicit Stubs(const std::shared_ptr<grpc::Channel>& channel)
        : maps(v1::MapService::NewStub(channel)),
          ingest(v1::IngestService::NewStub(channel)),
          query(v1::QueryService::NewStub(channel)) {}
    std::unique_ptr<v1::MapService::Stub> maps;
    std::unique_ptr<v1::IngestService::Stub> ingest;
    std::unique_ptr<v1::QueryService::Stub> query;
  };
  Stubs& stubs() {
    if (!stubs_) stubs_.emplace(daemon_->NewChannel());
    return *stubs_;
  }
  void Create(const v1::Map& map) {
    v1::CreateMapRequest request;
    *request.mutable_map() = map;
    v1::CreateMapResponse response;
    const grpc::Status status = stubs().maps->CreateMap(CallContext().get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  // Sends the batches on one stream; their responses.
  std::vector<v1::IngestResponse> Send(const std::vector<v1::IngestRequest>& batches) {
    auto context = CallContext();
    auto stream = stubs().ingest->Ingest(context.get());
    std::vector<v1::IngestResponse> responses;
    for (const auto& b : batches) {
      EXPECT_TRUE(stream->Write(b));
      v1::IngestResponse response;
      EXPECT_TRUE(stream->Read(&response));
      responses.push_back(response);
    }
    stream->WritesDone();
    EXPECT_TRUE(stream->Finish().ok());
    return responses;
  }
  // Every cell's model with its whole spectrum, serialised: equal strings are bit-identical models.
  std::vector<std::string> Models(const std::string& map) {
    std::vector<std::string> out;
    for (uint32_t z = 0; z < kNz; ++z) {
      for (uint32_t y = 0; y < kNy; ++y) {
        for (uint32_t x = 0; x < kNx; ++x) {
          v1::GetStateModelRequest request;
          request.set_map(map);
          request.mutable_state()->mutable_cell()->set_x(x);
          request.mutable_state()->mutable_cell()->set_y(y);
          request.mutable_state()->mutable_cell()->set_z(z);
          request.set_include_spectrum(true);
          v1::GetStateModelResponse response;
          const grpc::Status status = stubs().query->GetStateModel(CallContext().get(), request, &response);
          EXPECT_TRUE(status.ok()) << status.error_message();
          out.push_back(response.model().SerializeAsString());
        }
      }
    }
    return out;
  }

  std::optional<Stubs> stubs_;  // reset when the daemon restarts
};

TEST_F(CompactIngestTest, CompactScansGiveModelsBitIdenticalToCellObservationsAlsoAfterKill9) {
  Create(Grid("cells"));
  Create(Grid("compact"));
  std::mt19937_64 random(11);
  std::vector<v1::IngestRequest> cells, compact;
  uint64_t observations = 0;
  for (uint64_t s = 1; s <= 12; ++s) {
    const TestScan scan = RandomScan(random, s % 3 == 0);
    observations += scan.indices.size();
    cells.push_back(AsCells("cells", s, scan));
    compact.push_back(AsCompact("compact", s, scan));
  }
  uint64_t accepted = 0;
  for (const auto& r : Send(cells)) accepted += r.accepted();
  EXPECT_EQ(accepted, observations);
  accepted = 0;
  for (const auto& r : Send(compact)) {
    EXPECT_FALSE(r.has_error()) << r.error().message();
    accepted += r.accepted();
  }
  EXPECT_EQ(accepted, observations);
  const std::vector<std::string> want = Models("cells");
  EXPECT_EQ(Models("compact"), want);
  size_t observed = 0;
  for (const auto& m : want) observed += !m.empty();
  EXPECT_GT(observed, 200u);  // the comparison is about real models, not empty answers

  // Recovery replays the compact log records into the same models; retries stay duplicates.
  daemon_->Kill();
  stubs_.reset();
  StartDaemon();
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(Models("compact"), want);
  const auto again = Send({compact[4]});
  EXPECT_TRUE(again[0].duplicate());
}

TEST_F(CompactIngestTest, MalformedCompactCellsRefuseTheBatchNamingTheFieldAndTheStreamGoesOn) {
  Create(Grid("lab"));
  const auto with = [](uint64_t sequence, std::string indices, std::string occupied, std::string probabilities) {
    v1::IngestRequest request = Header("lab", sequence);
    request.mutable_compact()->set_indices(indices);
    request.mutable_compact()->set_occupied(occupied);
    request.mutable_compact()->set_probabilities(probabilities);
    return request;
  };
  const std::string two = EncodeIndexGaps(std::vector<uint64_t>{1, 2});
  const std::vector<std::pair<v1::IngestRequest, std::string>> cases = {
      {with(1, std::string("\x01\x00", 2), "\x01", ""), "compact.indices: the gap before cell 1 is 0"},
      {with(2, "\x05\x80", "\x01", ""), "compact.indices: the last varint is truncated"},
      {with(3, two, std::string("\x01\x00", 2), ""), "compact.occupied has 2 bytes for 2 cells"},
      {with(4, two, "", "a"), "compact.probabilities has 1 bytes for 2 cells"},
      {with(5, two, "\x01", "ab"), "compact: set occupied or probabilities, not both"},
  };
  std::vector<v1::IngestRequest> batches;
  for (const auto& c : cases) batches.push_back(c.first);
  batches.push_back(with(6, two, "\x03", ""));
  const auto responses = Send(batches);
  for (size_t i = 0; i < cases.size(); ++i) {
    EXPECT_EQ(responses[i].error().code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT)) << i;
    EXPECT_THAT(responses[i].error().message(), HasSubstr(cases[i].second));
    EXPECT_EQ(responses[i].accepted(), 0u);
  }
  EXPECT_FALSE(responses.back().has_error()) << responses.back().error().message();
  EXPECT_EQ(responses.back().accepted(), 2u);
}

TEST_F(CompactIngestTest, CellsPastTheGridAreRejectedOneByOneAsOutsideTheMap) {
  Create(Grid("lab"));
  v1::IngestRequest request = Header("lab", 1);
  const uint64_t last = kNx * kNy * kNz - 1;
  request.mutable_compact()->set_indices(EncodeIndexGaps(std::vector<uint64_t>{0, last, last + 1, last + 1000}));
  request.mutable_compact()->set_occupied(PackOccupiedBits(std::vector<float>{1, 1, 0, 1}));
  const auto response = Send({request})[0];
  EXPECT_FALSE(response.has_error()) << response.error().message();
  EXPECT_EQ(response.accepted(), 2u);
  EXPECT_EQ(response.rejected(), 2u);
  ASSERT_EQ(response.rejections_size(), 2);
  EXPECT_EQ(response.rejections(0).index(), 2u);
  EXPECT_EQ(response.rejections(0).reason(), v1::REJECT_REASON_OUTSIDE_MAP);
  EXPECT_EQ(response.rejections(1).index(), 3u);
}

TEST_F(CompactIngestTest, CompactCellsOnAGenericMapAreRefused) {
  v1::Map map = GenericMapSpec("doors");
  Create(map);
  v1::IngestRequest request = Header("doors", 1);
  request.mutable_compact()->set_indices(EncodeIndexGaps(std::vector<uint64_t>{1}));
  request.mutable_compact()->set_occupied("\x01");
  const auto response = Send({request})[0];
  EXPECT_EQ(response.error().code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(response.error().message(), HasSubstr("compact cells are only for grid maps"));
}

}  // namespace
}  // namespace fremen::testing
