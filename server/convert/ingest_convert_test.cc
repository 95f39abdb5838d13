#include "server/convert/ingest_convert.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "base/compact_scan.h"
#include "storage/state_names.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

storage::MapInfo Grid(uint32_t nx, uint32_t ny, uint32_t nz) {
  storage::MapInfo map;
  map.name = "lab";
  map.kind = storage::MapKind::kGrid;
  map.grid.resolution = 0.5;
  map.grid.origin = {-1, -1, 0};
  map.grid.size = {nx, ny, nz};
  return map;
}

storage::MapInfo Generic() {
  storage::MapInfo map;
  map.name = "doors";
  map.kind = storage::MapKind::kGeneric;
  return map;
}

v1::IngestRequest Request() {
  v1::IngestRequest request;
  request.set_writer_id(7);
  request.set_sequence(3);
  request.set_time(1.7e9);
  return request;
}

void AddCell(v1::IngestRequest& request, uint32_t x, uint32_t y, uint32_t z, float value) {
  v1::CellIndices* cells = request.mutable_cells()->mutable_cells();
  cells->add_x(x);
  cells->add_y(y);
  cells->add_z(z);
  request.mutable_cells()->add_values(value);
}

// The message of converting `request` for `map`, which must be InvalidArgument.
std::string ErrorOf(const storage::MapInfo& map, const v1::IngestRequest& request) {
  const absl::Status status = BatchFromRequest(map, request).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  return std::string(status.message());
}

TEST(IngestConvertTest, CellsBecomeGridKeys) {
  const storage::MapInfo map = Grid(10, 10, 4);
  v1::IngestRequest request = Request();
  AddCell(request, 1, 2, 3, 1.0f);
  AddCell(request, 9, 9, 0, 0.25f);
  auto batch = BatchFromRequest(map, request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_EQ(batch->writer_id, 7u);
  EXPECT_EQ(batch->sequence, 3u);
  EXPECT_EQ(batch->time, 1.7e9);
  const storage::GridKeys keys = map.grid.keys();
  EXPECT_THAT(batch->keys, ElementsAre(keys.Key(1, 2, 3), keys.Key(9, 9, 0)));
  EXPECT_THAT(batch->values, ElementsAre(1.0f, 0.25f));
  EXPECT_TRUE(storage::ValidateBatch(map, *batch).ok());
}

TEST(IngestConvertTest, CompactCellsBecomeTheKeysAndValuesOfTheSameCellsByIndex) {
  const storage::MapInfo map = Grid(10, 10, 4);
  v1::IngestRequest by_index = Request();
  v1::IngestRequest compact = Request();
  std::vector<uint64_t> indices;
  std::vector<float> values;
  for (uint32_t i = 5; i < 400; i += 1 + i % 3) {
    AddCell(by_index, i % 10, i / 10 % 10, i / 100, static_cast<float>(i % 2));
    indices.push_back(i);
    values.push_back(static_cast<float>(i % 2));
  }
  compact.mutable_compact()->set_indices(EncodeIndexGaps(indices));
  compact.mutable_compact()->set_occupied(PackOccupiedBits(values));
  auto want = BatchFromRequest(map, by_index);
  auto got = BatchFromRequest(map, compact);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->keys, want->keys);
  EXPECT_EQ(got->values, want->values);
  // The log keeps the bytes as they came.
  EXPECT_EQ(got->compact.indices, compact.compact().indices());
  EXPECT_EQ(got->compact.occupied, compact.compact().occupied());
  EXPECT_TRUE(storage::ValidateBatch(map, *got).ok());
  compact.mutable_compact()->set_occupied("");
  EXPECT_THAT(ErrorOf(map, compact), HasSubstr("compact: one of occupied or probabilities is required"));
  EXPECT_THAT(ErrorOf(Generic(), compact), HasSubstr("compact cells are only for grid maps"));
}

TEST(IngestConvertTest, CellsWithoutZAreInTheFirstLayer) {
  const storage::MapInfo map = Grid(10, 10, 1);
  v1::IngestRequest request = Request();
  request.mutable_cells()->mutable_cells()->add_x(4);
  request.mutable_cells()->mutable_cells()->add_y(5);
  request.mutable_cells()->add_values(1);
  auto batch = BatchFromRequest(map, request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_THAT(batch->keys, ElementsAre(map.grid.keys().Key(4, 5, 0)));
}

// Enough cells for the vector loops of the conversion (AVX2 or not, as the loader chose), not only
// their tails: each key is the one GridKeys gives for its cell, or the outside key, in each key
// layout, with z sent and without it.
TEST(IngestConvertTest, ManyCellsBecomeTheKeysOfEachCellInEveryLayout) {
  std::mt19937 rng(11);
  for (const uint32_t nz : {1u, 4u}) {
    for (const bool with_z : {true, false}) {
      const storage::MapInfo map = Grid(300, 200, nz);
      v1::IngestRequest request = Request();
      std::vector<uint64_t> want;
      for (int i = 0; i < 1003; ++i) {
        // About one cell in eight outside the grid, some far enough to alias inside once packed.
        const uint32_t x = rng() % 8 == 0 ? 300 + rng() % (1u << 22) : rng() % 300;
        const uint32_t y = rng() % 200, z = with_z ? rng() % (nz + 1) : 0;
        v1::CellIndices* cells = request.mutable_cells()->mutable_cells();
        cells->add_x(x);
        cells->add_y(y);
        if (with_z) cells->add_z(z);
        request.mutable_cells()->add_values(1.0f);
        want.push_back(x < 300 && z < nz ? map.grid.keys().Key(x, y, z) : kOutsideMapKey);
      }
      auto batch = BatchFromRequest(map, request);
      ASSERT_TRUE(batch.ok()) << batch.status();
      EXPECT_EQ(batch->keys, want) << "nz " << nz << " with z " << with_z;
    }
  }
}

TEST(IngestConvertTest, CellsOutsideTheGridAreRejectedByTheStoreAsOutsideTheMap) {
  const storage::MapInfo map = Grid(10, 10, 4);
  v1::IngestRequest request = Request();
  AddCell(request, 10, 0, 0, 1);
  AddCell(request, 0, 0, 4, 1);
  AddCell(request, (1u << 21) + 1, 1, 1, 1);  // would alias cell (1, 1, 1) once packed into 21 bits
  AddCell(request, 3, 3, 3, 1);
  auto batch = BatchFromRequest(map, request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  std::vector<uint8_t> accept;
  const storage::BatchAck ack = storage::Classify(map, *batch, accept);
  EXPECT_EQ(ack.accepted, 1u);
  EXPECT_EQ(ack.rejected, 3u);
  ASSERT_EQ(ack.rejections.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(ack.rejections[i].index, i);
    EXPECT_EQ(ack.rejections[i].reason, storage::RejectReason::kOutsideMap);
  }
}

TEST(IngestConvertTest, PointsBecomeTheirCellsAndOutsidePointsAreRejected) {
  const storage::MapInfo map = Grid(10, 10, 1);  // x, y in [-1, 4) m
  v1::IngestRequest request = Request();
  v1::Points* points = request.mutable_points()->mutable_points();
  for (double x : {-0.9, 3.9, 4.1, std::nan("")}) {
    points->add_x(x);
    points->add_y(0.2);
    request.mutable_points()->add_values(1);
  }
  auto batch = BatchFromRequest(map, request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  const storage::GridKeys keys = map.grid.keys();
  EXPECT_THAT(batch->keys, ElementsAre(keys.Key(0, 2, 0), keys.Key(9, 2, 0), kOutsideMapKey, kOutsideMapKey));
  std::vector<uint8_t> accept;
  const storage::BatchAck ack = storage::Classify(map, *batch, accept);
  EXPECT_EQ(ack.accepted, 2u);
  EXPECT_EQ(ack.rejected, 2u);
  EXPECT_EQ(ack.rejections[0].reason, storage::RejectReason::kOutsideMap);
}

TEST(IngestConvertTest, StatesByIdCarryTheirLabels) {
  v1::IngestRequest request = Request();
  v1::StateObservations* states = request.mutable_states();
  for (uint64_t id : {11u, 12u, 13u}) states->add_ids(id);
  for (float v : {0.0f, 1.0f, 0.5f}) states->add_values(v);
  for (const char* name : {"door-a", "", ""}) states->add_names(name);
  for (const char* group : {"hall", "hall", ""}) states->add_groups(group);
  auto batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_THAT(batch->keys, ElementsAre(11u, 12u, 13u));
  EXPECT_THAT(batch->values, ElementsAre(0.0f, 1.0f, 0.5f));
  // The third has neither name nor group: no label.
  EXPECT_THAT(batch->labels, ElementsAre(storage::StateLabel{11, "door-a", "hall"}, storage::StateLabel{12, "", "hall"}));
}

TEST(IngestConvertTest, NamedStatesAreKeyedByTheirNamesId) {
  v1::IngestRequest request = Request();
  v1::NamedStateObservations* named = request.mutable_named_states();
  named->add_names("door-a");
  named->add_names("door-b");
  named->add_values(1);
  named->add_values(0);
  auto batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  const uint64_t a = storage::StateIdOfName("door-a"), b = storage::StateIdOfName("door-b");
  EXPECT_THAT(batch->keys, ElementsAre(a, b));
  EXPECT_THAT(batch->labels, ElementsAre(storage::StateLabel{a, "door-a", ""}, storage::StateLabel{b, "door-b", ""}));
}

TEST(IngestConvertTest, PatchOfFloats) {
  const storage::MapInfo map = Grid(10, 10, 1);
  v1::IngestRequest request = Request();
  v1::DensePatch* patch = request.mutable_patch();
  patch->mutable_origin()->set_x(2);
  patch->mutable_origin()->set_y(3);
  patch->mutable_size()->set_x(2);
  patch->mutable_size()->set_y(2);  // z unset: one layer
  for (float v : {0.0f, 1.0f, 0.5f, 1.0f}) patch->add_values(v);
  auto batch = BatchFromRequest(map, request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_EQ(batch->patch.origin, (std::array<uint32_t, 3>{2, 3, 0}));
  EXPECT_EQ(batch->patch.size, (std::array<uint32_t, 3>{2, 2, 1}));
  EXPECT_THAT(batch->patch.values, ElementsAre(0.0f, 1.0f, 0.5f, 1.0f));
  EXPECT_TRUE(batch->keys.empty());
  EXPECT_TRUE(storage::ValidateBatch(map, *batch).ok());
}

TEST(IngestConvertTest, PatchOfBytesIsByteOver255) {
  v1::IngestRequest request = Request();
  v1::DensePatch* patch = request.mutable_patch();
  patch->mutable_size()->set_x(3);
  patch->mutable_size()->set_y(1);
  patch->set_probabilities(std::string("\x00\xff\x33", 3));
  auto batch = BatchFromRequest(Grid(10, 10, 1), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_THAT(batch->patch.values, ElementsAre(0.0f, 1.0f, 0.2f));
}

TEST(IngestConvertTest, MismatchedLengthsNameTheField) {
  const storage::MapInfo grid = Grid(10, 10, 4);
  v1::IngestRequest request = Request();
  for (int i = 0; i < 4; ++i) AddCell(request, 1, 1, 1, 1);
  request.mutable_cells()->mutable_values()->RemoveLast();
  EXPECT_EQ(ErrorOf(grid, request), "cells.values has 3 values for 4 cells");

  request = Request();
  for (int i = 0; i < 4; ++i) AddCell(request, 1, 1, 1, 1);
  request.mutable_cells()->mutable_cells()->mutable_y()->RemoveLast();
  EXPECT_THAT(ErrorOf(grid, request), HasSubstr("cells.cells.y has 3 indices for 4 cells"));

  request = Request();
  for (int i = 0; i < 4; ++i) AddCell(request, 1, 1, 1, 1);
  request.mutable_cells()->mutable_cells()->mutable_z()->RemoveLast();
  EXPECT_THAT(ErrorOf(grid, request), HasSubstr("cells.cells.z has 3 indices for 4 cells"));

  request = Request();
  request.mutable_points()->mutable_points()->add_x(0);
  request.mutable_points()->mutable_points()->add_y(0);
  EXPECT_THAT(ErrorOf(grid, request), HasSubstr("points.values has 0 values for 1 points"));

  request = Request();
  request.mutable_states()->add_ids(1);
  request.mutable_states()->add_values(1);
  request.mutable_states()->add_groups("a");
  request.mutable_states()->add_groups("b");
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("states.groups has 2 groups for 1 ids"));

  request = Request();
  request.mutable_named_states()->add_names("a");
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("named_states.values has 0 values for 1 names"));

  request = Request();
  request.mutable_patch()->mutable_size()->set_x(2);
  request.mutable_patch()->mutable_size()->set_y(2);
  request.mutable_patch()->add_values(1);
  EXPECT_THAT(ErrorOf(grid, request), HasSubstr("patch.values has 1 values for 4 cells"));
  request.mutable_patch()->clear_values();
  request.mutable_patch()->set_probabilities("abc");
  EXPECT_THAT(ErrorOf(grid, request), HasSubstr("patch.probabilities has 3 bytes for 4 cells"));
  request.mutable_patch()->add_values(1);
  EXPECT_THAT(ErrorOf(grid, request), HasSubstr("not both"));
}

TEST(IngestConvertTest, HugePatchSizesDoNotWrapAround) {
  v1::IngestRequest request = Request();
  v1::DensePatch* patch = request.mutable_patch();
  patch->mutable_size()->set_x(1u << 31);
  patch->mutable_size()->set_y(1u << 31);
  patch->mutable_size()->set_z(4);  // 2^64 cells: 0 once wrapped
  EXPECT_THAT(ErrorOf(Grid(10, 10, 4), request), HasSubstr("patch.values has 0 values"));
}

TEST(IngestConvertTest, ObservationsMustSuitTheMapsKind) {
  v1::IngestRequest request = Request();
  AddCell(request, 1, 1, 0, 1);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("cells are only for grid maps"));
  request = Request();
  request.mutable_patch()->mutable_size()->set_x(1);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("only for grid maps"));
  request = Request();
  request.mutable_states()->add_ids(1);
  request.mutable_states()->add_values(1);
  EXPECT_THAT(ErrorOf(Grid(10, 10, 1), request), HasSubstr("states by id are only for generic maps"));
  request = Request();
  request.mutable_named_states()->add_names("a");
  request.mutable_named_states()->add_values(1);
  EXPECT_THAT(ErrorOf(Grid(10, 10, 1), request), HasSubstr("named_states are only for generic maps"));
  EXPECT_THAT(ErrorOf(Grid(10, 10, 1), Request()), HasSubstr("observations are required"));
}

TEST(IngestConvertTest, BadNamesAreRefused) {
  v1::IngestRequest request = Request();
  request.mutable_named_states()->add_names("");
  request.mutable_named_states()->add_values(1);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("named_states.names[0] is empty"));
  request.mutable_named_states()->set_names(0, std::string(300, 'n'));
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("named_states.names[0] has 300 bytes"));
}

TEST(IngestConvertTest, ValuesAreLeftForTheStoreToClassify) {
  v1::IngestRequest request = Request();
  AddCell(request, 1, 1, 0, std::nanf(""));
  AddCell(request, 1, 1, 0, 1.5f);
  AddCell(request, 1, 1, 0, -0.1f);
  const storage::MapInfo map = Grid(10, 10, 1);
  auto batch = BatchFromRequest(map, request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  std::vector<uint8_t> accept;
  const storage::BatchAck ack = storage::Classify(map, *batch, accept);
  EXPECT_EQ(ack.rejected, 3u);
  for (const storage::Rejection& r : ack.rejections) EXPECT_EQ(r.reason, storage::RejectReason::kValueOutOfRange);
}

v1::IngestRequest History(std::initializer_list<double> times) {
  v1::IngestRequest request = Request();
  request.clear_time();
  for (double t : times) {
    request.mutable_history()->add_times(t);
    request.mutable_history()->add_values(1.0f);
  }
  return request;
}

TEST(IngestConvertTest, OneStatesHistoryGivesEveryObservationItsIdAndTime) {
  v1::IngestRequest request = History({1.7e9, 1.7e9 + 60, 1.7e9 + 60});
  request.mutable_history()->add_ids(42);
  request.mutable_history()->add_names("front door");
  auto batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_THAT(batch->keys, ElementsAre(42u, 42u, 42u));
  EXPECT_THAT(batch->times, ElementsAre(1.7e9, 1.7e9 + 60, 1.7e9 + 60));
  EXPECT_EQ(batch->time, 0.0);
  ASSERT_EQ(batch->labels.size(), 1u);
  EXPECT_EQ(batch->labels[0].name, "front door");
  EXPECT_TRUE(storage::ValidateBatch(Generic(), *batch).ok());
}

// A fuzzer's finding: with no values there are no keys to take the label's from.
TEST(IngestConvertTest, AOneStateHistoryWithoutValuesStillLabelsItsState) {
  v1::IngestRequest request = History({});
  request.mutable_history()->add_ids(42);
  request.mutable_history()->add_names("front door");
  auto batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_TRUE(batch->keys.empty());
  ASSERT_EQ(batch->labels.size(), 1u);
  EXPECT_EQ(batch->labels[0].key, 42u);
  EXPECT_EQ(batch->labels[0].name, "front door");
  request.mutable_history()->clear_ids();
  batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  ASSERT_EQ(batch->labels.size(), 1u);
  EXPECT_EQ(batch->labels[0].key, storage::StateIdOfName("front door"));
}

TEST(IngestConvertTest, ManyStatesHistoryTakesAnIdPerObservation) {
  v1::IngestRequest request = History({5, 6});
  request.mutable_history()->add_ids(1);
  request.mutable_history()->add_ids(2);
  auto batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  EXPECT_THAT(batch->keys, ElementsAre(1u, 2u));
}

TEST(IngestConvertTest, AHistoryWithoutIdsIsOfItsNamedState) {
  v1::IngestRequest request = History({5, 6});
  request.mutable_history()->add_names("back door");
  request.mutable_history()->add_groups("doors");
  auto batch = BatchFromRequest(Generic(), request);
  ASSERT_TRUE(batch.ok()) << batch.status();
  const uint64_t id = storage::StateIdOfName("back door");
  EXPECT_THAT(batch->keys, ElementsAre(id, id));
  ASSERT_EQ(batch->labels.size(), 1u);
  EXPECT_EQ(batch->labels[0].key, id);
  EXPECT_EQ(batch->labels[0].group, "doors");
  request.mutable_history()->set_names(0, "");
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("history.names[0] is empty"));
}

TEST(IngestConvertTest, BadHistoriesNameTheField) {
  v1::IngestRequest request = History({1, 2, NAN});
  request.mutable_history()->add_ids(1);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("history.times[2]"));
  request = History({1, 2, 3});
  request.mutable_history()->add_ids(1);
  request.mutable_history()->add_ids(2);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("history.ids has 2 ids for 3 values"));
  request = History({1, 2});
  request.mutable_history()->add_ids(1);
  request.mutable_history()->add_values(0.0f);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("history.times has 2 times for 3 values"));
  request = History({1});
  request.mutable_history()->add_ids(1);
  request.set_time(4);
  EXPECT_THAT(ErrorOf(Generic(), request), HasSubstr("time must be 0"));
  request = History({1});
  request.mutable_history()->add_ids(1);
  EXPECT_THAT(ErrorOf(Grid(4, 4, 1), request), HasSubstr("only for generic maps"));
}

TEST(IngestConvertTest, AcksAndErrorsBecomeResponses) {
  storage::BatchAck ack;
  ack.sequence = 9;
  ack.accepted = 5;
  ack.rejected = 2;
  ack.rejections = {{1, storage::RejectReason::kOutsideMap}, {4, storage::RejectReason::kValueOutOfRange}};
  v1::IngestResponse response;
  AckToResponse(ack, response);
  EXPECT_EQ(response.sequence(), 9u);
  EXPECT_EQ(response.accepted(), 5u);
  EXPECT_EQ(response.rejected(), 2u);
  EXPECT_FALSE(response.duplicate());
  ASSERT_EQ(response.rejections_size(), 2);
  EXPECT_EQ(response.rejections(0).index(), 1u);
  EXPECT_EQ(response.rejections(0).reason(), v1::REJECT_REASON_OUTSIDE_MAP);
  EXPECT_EQ(response.rejections(1).reason(), v1::REJECT_REASON_VALUE_OUT_OF_RANGE);
  EXPECT_FALSE(response.has_error());

  v1::IngestResponse refused;
  ErrorToResponse(4, absl::InvalidArgumentError("time must be finite"), refused);
  EXPECT_EQ(refused.sequence(), 4u);
  EXPECT_EQ(refused.error().code(), static_cast<int>(absl::StatusCode::kInvalidArgument));
  EXPECT_EQ(refused.error().message(), "time must be finite");
}

}  // namespace
}  // namespace fremen::server
