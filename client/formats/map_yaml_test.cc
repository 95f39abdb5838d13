#include "client/formats/map_yaml.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

namespace fremen::formats {
namespace {

using ::testing::HasSubstr;

// As ROS 1 map_saver writes it.
constexpr char kMapSaverYaml[] =
    "image: office.pgm\n"
    "resolution: 0.050000\n"
    "origin: [-10.000000, -5.500000, 0.000000]\n"
    "negate: 0\n"
    "occupied_thresh: 0.65\n"
    "free_thresh: 0.196\n"
    "\n";

TEST(MapYamlTest, ParsesWhatMapSaverWrites) {
  absl::StatusOr<MapMetadata> m = ParseMapYaml(kMapSaverYaml, "office.yaml");
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->image, "office.pgm");
  EXPECT_DOUBLE_EQ(m->resolution, 0.05);
  EXPECT_DOUBLE_EQ(m->origin_x, -10);
  EXPECT_DOUBLE_EQ(m->origin_y, -5.5);
  EXPECT_DOUBLE_EQ(m->origin_yaw, 0);
  EXPECT_FALSE(m->negate);
  EXPECT_DOUBLE_EQ(m->occupied_thresh, 0.65);
  EXPECT_DOUBLE_EQ(m->free_thresh, 0.196);
  EXPECT_EQ(m->mode, MapMode::kTrinary);
}

TEST(MapYamlTest, ParsesNav2StyleWithQuotesCommentsAndMode) {
  absl::StatusOr<MapMetadata> m = ParseMapYaml(
      "# saved by nav2\nimage: \"my map.pgm\"  # the image\nmode: scale\nresolution: 0.1\n"
      "origin: [1, 2.5, 0]\nnegate: 1\n",
      "n.yaml");
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->image, "my map.pgm");
  EXPECT_EQ(m->mode, MapMode::kScale);
  EXPECT_TRUE(m->negate);
  EXPECT_DOUBLE_EQ(m->occupied_thresh, 0.65);  // defaults
  EXPECT_DOUBLE_EQ(m->free_thresh, 0.25);
}

TEST(MapYamlTest, ErrorsNameTheFileLineAndKey) {
  EXPECT_EQ(ParseMapYaml("image: a.pgm\norigin: [0, 0, 0]\n", "m.yaml").status().message(),
            "m.yaml: resolution is missing (a number is required)");
  EXPECT_EQ(ParseMapYaml("image: a.pgm\nresolution: abc\norigin: [0, 0, 0]\n", "m.yaml").status().message(),
            "m.yaml:2: resolution must be a number, got \"abc\"");
  EXPECT_THAT(ParseMapYaml("image: a.pgm\nresolution: -1\norigin: [0, 0, 0]\n", "m.yaml").status().message(),
              HasSubstr("m.yaml:2: resolution must be > 0"));
  EXPECT_EQ(ParseMapYaml("image: a.pgm\nresolution: 1\norigin: [0, 0]\n", "m.yaml").status().message(),
            "m.yaml:3: origin must have 3 numbers [x, y, yaw], got 2");
  EXPECT_THAT(ParseMapYaml("image: a.pgm\nresolution: 1\norigin: 0\n", "m.yaml").status().message(),
              HasSubstr("m.yaml:3: origin must be [x, y, yaw]"));
  EXPECT_THAT(ParseMapYaml("resolution: 1\norigin: [0, 0, 0]\n", "m.yaml").status().message(),
              HasSubstr("m.yaml: image is missing"));
  EXPECT_THAT(ParseMapYaml("image: a\nresolution: 1\norigin: [0,0,0]\nfree_thresh: 0.7\n", "m.yaml").status().message(),
              HasSubstr("m.yaml:4: free_thresh must be below occupied_thresh"));
  EXPECT_THAT(ParseMapYaml("image: a\nresolution: 1\norigin: [0,0,0]\nmode: raw\n", "m.yaml").status().message(),
              HasSubstr("m.yaml:4: mode must be trinary or scale"));
  EXPECT_THAT(ParseMapYaml("image: a\nresolution: 1\nresolution: 2\n", "m.yaml").status().message(),
              HasSubstr("m.yaml:3: resolution is given twice"));
  EXPECT_THAT(ParseMapYaml("image a.pgm\n", "m.yaml").status().message(), HasSubstr("m.yaml:1: expected `key: value`"));
}

TEST(MapYamlTest, WriteThenReadGivesTheSameMetadata) {
  MapMetadata m;
  m.image = "region.pgm";
  m.resolution = 0.05;
  m.origin_x = 12.345678901234;
  m.origin_y = -0.1;
  m.occupied_thresh = 0.65;
  m.free_thresh = 0.196;
  const std::string path = (std::filesystem::temp_directory_path() / "fremen_map_yaml_test.yaml").string();
  ASSERT_TRUE(WriteMapYaml(path, m).ok());
  absl::StatusOr<MapMetadata> read = ReadMapYaml(path);
  std::remove(path.c_str());
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->image, m.image);
  EXPECT_EQ(read->resolution, m.resolution);
  EXPECT_EQ(read->origin_x, m.origin_x);  // exact: the cells must land where they were
  EXPECT_EQ(read->origin_y, m.origin_y);
  EXPECT_EQ(read->free_thresh, m.free_thresh);
  EXPECT_EQ(read->mode, MapMode::kTrinary);
}

TEST(MapYamlTest, ImagePathIsRelativeToTheYaml) {
  MapMetadata m;
  m.image = "a.pgm";
  EXPECT_EQ(ResolveImagePath("/maps/x/office.yaml", m), "/maps/x/a.pgm");
  m.image = "/abs/b.pgm";
  EXPECT_EQ(ResolveImagePath("/maps/x/office.yaml", m), "/abs/b.pgm");
}

}  // namespace
}  // namespace fremen::formats
