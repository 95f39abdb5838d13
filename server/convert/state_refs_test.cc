#include "server/convert/state_refs.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "storage/state_names.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

storage::MapInfo Grid() {
  storage::MapInfo map;
  map.name = "lab";
  map.kind = storage::MapKind::kGrid;
  map.grid.resolution = 0.5;
  map.grid.origin = {10, 20, 0};
  map.grid.size = {40, 30, 1};
  return map;
}

storage::MapInfo Generic() {
  storage::MapInfo map;
  map.name = "doors";
  map.kind = storage::MapKind::kGeneric;
  return map;
}

absl::Status ErrorOf(const storage::MapInfo& map, const v1::StateRefs& refs) {
  return KeysOfRefs(map, refs, "states").status();
}

TEST(StateRefsTest, CellsByIndex) {
  v1::StateRefs refs;
  refs.mutable_cells()->add_x(3);
  refs.mutable_cells()->add_y(4);
  refs.mutable_cells()->add_x(39);
  refs.mutable_cells()->add_y(29);
  const storage::MapInfo map = Grid();
  auto keys = KeysOfRefs(map, refs, "states");
  ASSERT_TRUE(keys.ok()) << keys.status();
  EXPECT_THAT(*keys, ElementsAre(map.grid.keys().Key(3, 4, 0), map.grid.keys().Key(39, 29, 0)));
  EXPECT_EQ(RefCount(refs), 2u);
}

TEST(StateRefsTest, CellsOutsideTheGridAreOutOfRange) {
  v1::StateRefs refs;
  for (uint32_t x : {1u, 40u}) {
    refs.mutable_cells()->add_x(x);
    refs.mutable_cells()->add_y(0);
  }
  const absl::Status s = ErrorOf(Grid(), refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(s.message(), HasSubstr("states.cells[1] = (40, 0, 0) is outside"));
  refs.mutable_cells()->add_z(0);
  refs.mutable_cells()->add_z(0);
  refs.mutable_cells()->set_x(1, 0);
  refs.mutable_cells()->set_z(1, 1);  // a 2-D grid has only z = 0
  EXPECT_EQ(ErrorOf(Grid(), refs).code(), absl::StatusCode::kOutOfRange);
}

// A batch of cells takes a path of its own (one check of the whole list, then the keys): every key
// must be the one cell's Key, in a 2-D grid with z left out or given, and in a 3-D grid.
TEST(StateRefsTest, ManyCellsGetTheirOwnKeys) {
  for (const uint32_t size_z : {1u, 5u}) {
    for (const bool with_z : {false, true}) {
      storage::MapInfo map = Grid();
      map.grid.size[2] = size_z;
      v1::StateRefs refs;
      std::vector<uint64_t> expected;
      for (uint32_t i = 0; i < 1000; ++i) {
        const uint32_t x = (i * 7) % 40, y = (i * 13) % 30, z = with_z ? (i * 3) % size_z : 0;
        refs.mutable_cells()->add_x(x);
        refs.mutable_cells()->add_y(y);
        if (with_z) refs.mutable_cells()->add_z(z);
        expected.push_back(map.grid.keys().Key(x, y, z));
      }
      auto keys = KeysOfRefs(map, refs, "states");
      ASSERT_TRUE(keys.ok()) << keys.status();
      EXPECT_EQ(*keys, expected) << "size_z " << size_z << (with_z ? ", z given" : ", z left out");
    }
  }
}

// In a long list, the error names the first cell outside, whichever axis it is outside on.
TEST(StateRefsTest, TheFirstCellOutsideALongListIsNamed) {
  storage::MapInfo map = Grid();
  map.grid.size[2] = 4;
  for (const int axis : {0, 1, 2}) {
    v1::StateRefs refs;
    for (uint32_t i = 0; i < 1000; ++i) {
      refs.mutable_cells()->add_x(i % 40);
      refs.mutable_cells()->add_y(i % 30);
      refs.mutable_cells()->add_z(i % 4);
    }
    const std::array<uint32_t, 3> outside = {40, 30, 4};
    for (const int at : {617, 900}) {
      v1::CellIndices& cells = *refs.mutable_cells();
      (axis == 0 ? cells.mutable_x() : axis == 1 ? cells.mutable_y() : cells.mutable_z())->Set(at, outside[axis]);
    }
    const absl::Status s = ErrorOf(map, refs);
    EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange) << "axis " << axis;
    EXPECT_THAT(s.message(), HasSubstr("states.cells[617] = ")) << "axis " << axis;
  }
}

TEST(StateRefsTest, MismatchedLengthsNameTheArray) {
  v1::StateRefs refs;
  refs.mutable_cells()->add_x(1);
  refs.mutable_cells()->add_x(2);
  refs.mutable_cells()->add_y(1);
  absl::Status s = ErrorOf(Grid(), refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("states.cells.y has 1 elements but states.cells.x has 2"));
  refs.mutable_cells()->add_y(1);
  refs.mutable_cells()->add_z(0);
  s = ErrorOf(Grid(), refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("states.cells.z"));
}

TEST(StateRefsTest, PointsByMetricPosition) {
  v1::StateRefs refs;
  refs.mutable_points()->add_x(10.0 + 0.5 * 3 + 0.1);
  refs.mutable_points()->add_y(20.0 + 0.5 * 7 + 0.4);
  const storage::MapInfo map = Grid();
  auto keys = KeysOfRefs(map, refs, "states");
  ASSERT_TRUE(keys.ok()) << keys.status();
  EXPECT_THAT(*keys, ElementsAre(map.grid.keys().Key(3, 7, 0)));

  refs.mutable_points()->set_x(0, 9.9);
  absl::Status s = ErrorOf(map, refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(s.message(), HasSubstr("states.points[0]"));
  refs.mutable_points()->set_x(0, std::numeric_limits<double>::quiet_NaN());
  s = ErrorOf(map, refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("states.points[0]"));
}

TEST(StateRefsTest, ExactlyOneList) {
  v1::StateRefs refs;
  absl::Status s = ErrorOf(Grid(), refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("states is empty"));
  refs.add_ids(1);
  refs.mutable_cells()->add_x(1);
  refs.mutable_cells()->add_y(1);
  s = ErrorOf(Grid(), refs);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("sets ids and cells"));
}

TEST(StateRefsTest, KindsOfReferenceFollowTheMap) {
  v1::StateRefs ids;
  ids.add_ids(7);
  absl::Status s = ErrorOf(Grid(), ids);
  EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(s.message(), HasSubstr("states.ids"));
  v1::StateRefs cells;
  cells.mutable_cells()->add_x(1);
  cells.mutable_cells()->add_y(1);
  s = ErrorOf(Generic(), cells);
  EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(s.message(), HasSubstr("states.cells"));
}

TEST(StateRefsTest, GenericByIdAndName) {
  v1::StateRefs refs;
  refs.add_ids(7);
  refs.add_ids(~uint64_t{0});
  auto keys = KeysOfRefs(Generic(), refs, "states");
  ASSERT_TRUE(keys.ok());
  EXPECT_THAT(*keys, ElementsAre(7u, ~uint64_t{0}));

  v1::StateRefs names;
  names.add_names("kitchen door");
  keys = KeysOfRefs(Generic(), names, "states");
  ASSERT_TRUE(keys.ok());
  EXPECT_THAT(*keys, ElementsAre(storage::StateIdOfName("kitchen door")));
  names.add_names("");
  const absl::Status s = ErrorOf(Generic(), names);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("states.names[1] is empty"));
}

TEST(StateRefsTest, OneRef) {
  v1::StateRef ref;
  absl::Status s = KeyOfRef(Grid(), ref, "state").status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("state is required"));
  ref.mutable_cell()->set_x(5);
  ref.mutable_cell()->set_y(6);
  EXPECT_EQ(*KeyOfRef(Grid(), ref, "state"), Grid().grid.keys().Key(5, 6, 0));
  ref.mutable_cell()->set_y(30);
  s = KeyOfRef(Grid(), ref, "state").status();
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(s.message(), HasSubstr("state.cell"));
  ref.set_name("door");
  EXPECT_EQ(KeyOfRef(Grid(), ref, "state").status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(*KeyOfRef(Generic(), ref, "state"), storage::StateIdOfName("door"));
  ref.set_id(42);
  EXPECT_EQ(*KeyOfRef(Generic(), ref, "state"), 42u);
}

}  // namespace
}  // namespace fremen::server
