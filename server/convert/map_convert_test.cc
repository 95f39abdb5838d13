#include "server/convert/map_convert.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

v1::Map GridMap() {
  v1::Map map;
  map.set_name("lab");
  map.set_kind(v1::MAP_KIND_GRID);
  map.mutable_grid()->set_resolution(0.1);
  map.mutable_grid()->mutable_size()->set_x(200);
  map.mutable_grid()->mutable_size()->set_y(100);
  return map;
}

// The message of converting `map`, which must be InvalidArgument.
std::string ErrorOf(const v1::Map& map) {
  const absl::Status status = MapInfoFromProto(map).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  return std::string(status.message());
}

TEST(MapConvertTest, UnsetFieldsTakeTheDefaults) {
  auto info = MapInfoFromProto(GridMap());
  ASSERT_TRUE(info.ok()) << info.status();
  const storage::MapInfo defaults;
  EXPECT_EQ(info->name, "lab");
  EXPECT_EQ(info->kind, storage::MapKind::kGrid);
  EXPECT_EQ(info->grid.size, (std::array<uint32_t, 3>{200, 100, 1}));  // z unset: 2-D
  EXPECT_EQ(info->periods, defaults.periods);
  EXPECT_EQ(info->max_order, defaults.max_order);
  EXPECT_EQ(info->persistence, defaults.persistence);
  EXPECT_EQ(info->error_half_life, defaults.error_half_life);
  EXPECT_EQ(info->criterion, defaults.criterion);
  EXPECT_EQ(info->criterion, model::ErrorCriterion::kThreshold);
  EXPECT_EQ(info->order_rule, model::OrderRule{});
  EXPECT_EQ(info->order_rule.selection, model::OrderSelection::kMargin);
  EXPECT_EQ(info->lossless_sampling_period, 0);
}

TEST(MapConvertTest, ExplicitZerosAreKept) {
  v1::Map map = GridMap();
  map.set_max_order(0);
  map.set_persistence(false);
  map.set_error_half_life_seconds(0);
  auto info = MapInfoFromProto(map);
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->max_order, 0u);
  EXPECT_FALSE(info->persistence);
  EXPECT_EQ(info->error_half_life, 0);
}

TEST(MapConvertTest, RoundTripsEveryField) {
  storage::MapInfo info;
  info.name = "corridor.3d";
  info.kind = storage::MapKind::kGrid;
  info.grid.resolution = 0.25;
  info.grid.origin = {-10, -5.5, 0.5};
  info.grid.size = {64, 32, 8};
  info.periods.explicit_periods = {86400, 43200, 3600};
  info.max_order = 3;
  info.persistence = false;
  info.error_half_life = 3600;
  info.criterion = model::ErrorCriterion::kThreshold;
  info.order_rule = model::OrderRule{model::OrderSelection::kPaper, 0.25, 0.125};
  info.lossless_sampling_period = 60;
  info.lossless_origin = 1.7e9;
  info.shards = 4;
  v1::Map proto;
  MapInfoToProto(info, proto);
  EXPECT_EQ(proto.create_time().seconds(), 0);
  auto back = MapInfoFromProto(proto);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(*back, info);
}

// Explicit periods leave the harmonic fields unused, but they are kept (GetMap shows them as
// given), so the count must still fit the catalog's record: a count beyond it once made a map that
// was created and then failed at the next start, its record undecodable.
TEST(MapConvertTest, APeriodCountTheCatalogCannotKeepIsRefusedEvenWithExplicitPeriods) {
  v1::Map map = GridMap();
  map.mutable_periods()->set_count(4294967240u);
  map.mutable_periods()->add_explicit_seconds(86400);
  EXPECT_EQ(ErrorOf(map), "map.periods.count: must be in [1, 65535], got 4294967240");

  map = GridMap();
  map.mutable_periods()->set_count(65535);
  map.mutable_periods()->add_explicit_seconds(86400);
  auto info = MapInfoFromProto(map);
  ASSERT_TRUE(info.ok()) << info.status();
  auto decoded = storage::DecodeMapInfo(storage::EncodeMapInfo(*info));
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, *info);
}

TEST(MapConvertTest, GenericMapRoundTripsWithoutGrid) {
  storage::MapInfo info;
  info.name = "doors";
  info.kind = storage::MapKind::kGeneric;
  info.periods.longest = 86400;
  info.periods.count = 12;
  info.created_unix = 1700000000;
  v1::Map proto;
  MapInfoToProto(info, proto);
  EXPECT_FALSE(proto.has_grid());
  EXPECT_EQ(proto.create_time().seconds(), 1700000000);
  auto back = MapInfoFromProto(proto);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->periods, info.periods);
  EXPECT_EQ(back->kind, storage::MapKind::kGeneric);
}

TEST(MapConvertTest, ProtoOnlyRulesNameTheField) {
  v1::Map map = GridMap();
  map.set_kind(v1::MAP_KIND_UNSPECIFIED);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.kind is required"));
  map.set_kind(static_cast<v1::MapKind>(9));
  EXPECT_THAT(ErrorOf(map), StartsWith("map.kind: unknown value 9"));

  map = GridMap();
  map.clear_grid();
  EXPECT_THAT(ErrorOf(map), StartsWith("map.grid is required"));
  map = GridMap();
  map.set_kind(v1::MAP_KIND_GENERIC);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.grid must be unset"));

  map = GridMap();
  map.set_criterion(static_cast<v1::ErrorCriterion>(5));
  EXPECT_THAT(ErrorOf(map), StartsWith("map.criterion: unknown value 5"));
}

// Storage validates; its messages come back under the proto's field names.
TEST(MapConvertTest, StorageErrorsUseTheProtoFieldNames) {
  v1::Map map = GridMap();
  map.set_name("");
  EXPECT_THAT(ErrorOf(map), StartsWith("map.name must be"));
  map.set_name("no spaces");
  EXPECT_THAT(ErrorOf(map), StartsWith("map.name may hold only"));

  map = GridMap();
  map.mutable_grid()->set_resolution(0);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.grid.resolution must be a positive number"));
  map = GridMap();
  map.mutable_grid()->set_resolution(std::nan(""));
  EXPECT_THAT(ErrorOf(map), StartsWith("map.grid.resolution"));
  map = GridMap();
  map.mutable_grid()->mutable_origin()->set_y(INFINITY);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.grid.origin.y must be finite"));
  map = GridMap();
  map.mutable_grid()->mutable_size()->set_x(0);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.grid.size.x must be in [1, 2097152]"));

  map = GridMap();
  map.mutable_periods()->set_longest_seconds(-1);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.periods.longest_seconds:"));
  map = GridMap();
  map.mutable_periods()->set_count(0);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.periods.count:"));
  map = GridMap();
  map.mutable_periods()->add_explicit_seconds(3600);
  map.mutable_periods()->add_explicit_seconds(-5);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.periods.explicit_seconds[1] must be a positive number"));

  map = GridMap();
  map.set_max_order(65);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.max_order must be in [0, 64]"));
  map = GridMap();
  map.set_error_half_life_seconds(-1);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.error_half_life_seconds must be"));
  map = GridMap();
  map.set_lossless_sampling_seconds(-60);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.lossless_sampling_seconds must be"));
  map = GridMap();
  map.set_lossless_origin(NAN);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.lossless_origin must be finite"));
  map = GridMap();
  map.set_shards(257);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.shards must be in [1, 256]"));
  map = GridMap();
  map.set_order_margin(-0.5);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.order_margin must be"));
  map = GridMap();
  map.set_order_temperature(0);
  EXPECT_THAT(ErrorOf(map), StartsWith("map.order_temperature must be"));
  map = GridMap();
  map.set_order_selection(static_cast<v1::OrderSelection>(42));
  EXPECT_THAT(ErrorOf(map), StartsWith("map.order_selection: unknown value 42"));
}

TEST(MapConvertTest, OnlyInvalidArgumentIsRenamed) {
  const absl::Status exists = absl::AlreadyExistsError("name taken");
  EXPECT_EQ(RenameStorageFields(exists), exists);
  EXPECT_EQ(RenameStorageFields(absl::InvalidArgumentError("something else")).message(), "map: something else");
}

}  // namespace
}  // namespace fremen::server
