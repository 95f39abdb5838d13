#include "storage/map_info.h"

#include <gtest/gtest.h>

#include <random>

namespace fremen::storage {
namespace {

MapInfo Office() {
  MapInfo info;
  info.name = "office-3d";
  info.id = 42;
  info.grid.resolution = 0.1;
  info.grid.origin = {-5, -5, 0};
  info.grid.size = {100, 100, 20};
  info.shards = 2;
  info.created_unix = 1700000000;
  return info;
}

TEST(MapInfoTest, EncodingRoundTrips) {
  MapInfo info = Office();
  info.periods.explicit_periods = {86400, 43200};
  info.lossless_sampling_period = 5;
  auto decoded = DecodeMapInfo(EncodeMapInfo(info));
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, info);
  info.order_rule = model::OrderRule{model::OrderSelection::kMargin, 0.004, 0.5};
  decoded = DecodeMapInfo(EncodeMapInfo(info));
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(decoded->order_rule, info.order_rule);
}

TEST(MapInfoTest, NewMapsTakeTheMarginRule) {
  const MapInfo info;
  EXPECT_EQ(info.order_rule.selection, model::OrderSelection::kMargin);
  EXPECT_EQ(info.order_rule.margin, 0.001);
  EXPECT_EQ(info.criterion, model::ErrorCriterion::kThreshold);
  EXPECT_EQ(info.error_half_life, 7 * 86400.0);
}

// A version-1 record (before the order rule was stored) is the version-2 encoding without its last
// 17 bytes: it reads back with the rule those maps were made with, margin 0.001.
TEST(MapInfoTest, VersionOneRecordsKeepTheMarginRule) {
  MapInfo info = Office();
  info.criterion = model::ErrorCriterion::kThreshold;
  info.error_half_life = 7 * 86400.0;
  std::string bytes = EncodeMapInfo(info);
  ASSERT_EQ(bytes[0], 2);
  bytes[0] = 1;
  bytes.resize(bytes.size() - 17);
  auto decoded = DecodeMapInfo(bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(decoded->order_rule, (model::OrderRule{model::OrderSelection::kMargin, 0.001}));
  EXPECT_EQ(decoded->criterion, model::ErrorCriterion::kThreshold);
  EXPECT_EQ(decoded->error_half_life, 7 * 86400.0);
  auto settings = ModelSettingsOf(*decoded);
  ASSERT_TRUE(settings.ok());
  EXPECT_EQ(settings->order_rule.selection, model::OrderSelection::kMargin);
  bytes[0] = 3;
  EXPECT_TRUE(absl::IsDataLoss(DecodeMapInfo(bytes).status()));
}

TEST(MapInfoTest, ValidationNamesTheField) {
  const auto message_of = [](MapInfo info) { return std::string(ValidateMapInfo(info).message()); };
  MapInfo bad = Office();
  bad.name = "no spaces";
  EXPECT_NE(message_of(bad).find("name"), std::string::npos);
  bad = Office();
  bad.grid.resolution = -1;
  EXPECT_NE(message_of(bad).find("grid.resolution"), std::string::npos);
  bad = Office();
  bad.grid.size[2] = 0;
  EXPECT_NE(message_of(bad).find("grid.size.z"), std::string::npos);
  bad = Office();
  bad.max_order = 65;
  EXPECT_NE(message_of(bad).find("max_order"), std::string::npos);
  bad = Office();
  bad.periods.count = 0;
  EXPECT_NE(message_of(bad).find("periods"), std::string::npos);
  bad = Office();
  bad.periods.count = 65536;  // more than the catalog's encoding keeps: refused even when unused
  bad.periods.explicit_periods = {86400, 3600};
  EXPECT_EQ(message_of(bad), "periods: period count must be in [1, 65535], got 65536");
  bad = Office();
  bad.error_half_life = NAN;
  EXPECT_NE(message_of(bad).find("error_half_life"), std::string::npos);
  bad = Office();
  bad.order_rule.selection = static_cast<model::OrderSelection>(7);
  EXPECT_NE(message_of(bad).find("order_selection"), std::string::npos);
  bad = Office();
  bad.order_rule.margin = -0.1;
  EXPECT_NE(message_of(bad).find("order_margin"), std::string::npos);
  bad = Office();
  bad.order_rule.temperature = 0;
  EXPECT_NE(message_of(bad).find("order_temperature"), std::string::npos);
  EXPECT_TRUE(ValidateMapInfo(Office()).ok());
}

TEST(MapInfoTest, CellOfAPoint) {
  const MapInfo info = Office();
  const auto cell = info.grid.CellOf(0.05, -4.95, 1.99);
  ASSERT_TRUE(cell.has_value());
  EXPECT_EQ((*cell)[0], 50u);
  EXPECT_EQ((*cell)[1], 0u);
  EXPECT_EQ((*cell)[2], 19u);
  EXPECT_FALSE(info.grid.CellOf(-5.01, 0, 0).has_value());
  EXPECT_FALSE(info.grid.CellOf(0, 0, 2.0).has_value());
  EXPECT_FALSE(info.grid.CellOf(NAN, 0, 0).has_value());
}

TEST(MapInfoTest, DamagedBytesAreDataLossNeverACrash) {
  const std::string good = EncodeMapInfo(Office());
  for (size_t n = 0; n < good.size(); ++n) {
    EXPECT_TRUE(absl::IsDataLoss(DecodeMapInfo(good.substr(0, n)).status())) << n;
  }
  std::mt19937 rng(3);
  for (int i = 0; i < 3000; ++i) {
    std::string bytes = good;
    bytes[rng() % bytes.size()] ^= static_cast<char>(1 << (rng() % 8));
    auto decoded = DecodeMapInfo(bytes);
    if (decoded.ok()) {
      EXPECT_TRUE(ValidateMapInfo(*decoded).ok());
    }
  }
}

}  // namespace
}  // namespace fremen::storage
