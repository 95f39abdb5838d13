#include "client/formats/map_server_snapshots.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "client/formats/occupancy_pixels.h"
#include "client/formats/pgm.h"
#include "client/formats/png_decode.h"
#include "client/formats/region_export.h"
#include "testing/temp_dir.h"

namespace fremen::formats {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class SnapshotDirTest : public ::testing::Test {
 protected:

  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  // A 3 × 2 trinary map: top row occupied, free, unknown; bottom row free, free, occupied.
  void WriteSnapshot(const std::string& stem, double origin_x = 1.0) {
    Image image(3, 2, 1);
    image.pixels = {kPixelOccupied, kPixelFree, kPixelUnknown, kPixelFree, kPixelFree, kPixelOccupied};
    ASSERT_TRUE(WritePgm((dir_ / (stem + ".pgm")).string(), image).ok());
    Write(stem + ".yaml", "image: " + stem + ".pgm\nresolution: 0.5\norigin: [" + std::to_string(origin_x) +
                              ", 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  }

  fremen::testing::TempDir temp_;
  const fs::path dir_{temp_.path()};
};

TEST(TimeFromFileNameTest, TheNumberEndingTheName) {
  EXPECT_EQ(*TimeFromFileName("/d/office_1700000000.yaml"), 1700000000);
  EXPECT_EQ(*TimeFromFileName("/d/1700000000.5.yaml"), 1700000000.5);
  EXPECT_EQ(*TimeFromFileName("/d/office-42.yaml"), 42);  // '-' separates words
  EXPECT_EQ(*TimeFromFileName("/d/-42.yaml"), -42);
  EXPECT_THAT(TimeFromFileName("/d/office.yaml").status().message(),
              HasSubstr("/d/office.yaml: the file name does not end with its time"));
}

TEST_F(SnapshotDirTest, ListsByTimeFromNamesOrFromATimesFile) {
  WriteSnapshot("office_200");
  WriteSnapshot("office_100");
  absl::StatusOr<std::vector<SnapshotFile>> files = ListSnapshots(dir_.string(), "");
  ASSERT_TRUE(files.ok()) << files.status();
  ASSERT_EQ(files->size(), 2u);
  EXPECT_EQ((*files)[0].time, 100);
  EXPECT_EQ(fs::path((*files)[1].yaml_path).filename(), "office_200.yaml");

  const std::string times = Write("times.txt", "# file time\noffice_200.yaml 7.5\n");
  files = ListSnapshots(dir_.string(), times);
  ASSERT_TRUE(files.ok()) << files.status();
  ASSERT_EQ(files->size(), 1u);
  EXPECT_EQ((*files)[0].time, 7.5);

  EXPECT_THAT(ListSnapshots(dir_.string(), Write("bad.txt", "office_200.yaml soon\n")).status().message(),
              HasSubstr("bad.txt:1: TIME must be a finite number"));
  EXPECT_THAT(ListSnapshots(dir_.string(), Write("missing.txt", "nope.yaml 1\n")).status().message(),
              HasSubstr("missing.txt:1: no file"));
  EXPECT_THAT(ListSnapshots((dir_ / "none").string(), "").status().message(), HasSubstr("not a directory"));
  Write("untimed.yaml", "image: x.pgm\n");
  EXPECT_THAT(ListSnapshots(dir_.string(), "").status().message(), HasSubstr("untimed.yaml: the file name"));
}

TEST_F(SnapshotDirTest, CellsAreFlippedAndPlacedOnTheGrid) {
  WriteSnapshot("s_1");
  absl::StatusOr<Snapshot> snapshot = ReadSnapshot((dir_ / "s_1.yaml").string());
  ASSERT_TRUE(snapshot.ok()) << snapshot.status();
  // The grid starts at (0, 0) with 0.5 m cells: the snapshot's origin (1, 2) is cell (2, 4).
  const GridPlacement grid{0.5, 0.0, 0.0, 10, 10};
  uint32_t ox, oy;
  ASSERT_TRUE(PlaceSnapshot(*snapshot, grid, "s_1.yaml", ox, oy).ok());
  EXPECT_EQ(ox, 2u);
  EXPECT_EQ(oy, 4u);
  const std::vector<CellBatch> batches = SnapshotBatches(*snapshot, 5.0, ox, oy, 3);
  ASSERT_EQ(batches.size(), 2u);  // 5 known cells, at most 3 per batch
  EXPECT_EQ(batches[0].time, 5.0);
  // Image row 0 (top) is grid row oy + 1; the unknown pixel is skipped.
  EXPECT_EQ(batches[0].x, (std::vector<uint32_t>{2, 3, 2}));
  EXPECT_EQ(batches[0].y, (std::vector<uint32_t>{5, 5, 4}));
  EXPECT_EQ(batches[0].values, (std::vector<float>{1, 0, 0}));
  EXPECT_EQ(batches[1].values, (std::vector<float>{0, 1}));

  EXPECT_THAT(PlaceSnapshot(*snapshot, {0.25, 0, 0, 10, 10}, "s_1.yaml", ox, oy).message(),
              HasSubstr("s_1.yaml: resolution 0.5 differs"));
  EXPECT_THAT(PlaceSnapshot(*snapshot, {0.5, 0.1, 0, 10, 10}, "s_1.yaml", ox, oy).message(),
              HasSubstr("not on a cell corner"));
  EXPECT_THAT(PlaceSnapshot(*snapshot, {0.5, 0, 0, 4, 10}, "s_1.yaml", ox, oy).message(),
              HasSubstr("does not lie inside the map's 4x10 grid"));
}

TEST_F(SnapshotDirTest, RotatedMapsAreRefused) {
  Write("r_1.yaml", "image: r.pgm\nresolution: 1\norigin: [0, 0, 0.5]\n");
  EXPECT_THAT(ReadSnapshot((dir_ / "r_1.yaml").string()).status().message(), HasSubstr("origin yaw must be 0"));
}

TEST_F(SnapshotDirTest, ExportedRegionReadsBackAsTheSameCells) {
  ProbabilityPlane plane;
  plane.width = 3;
  plane.height = 2;
  plane.p = {0.0f, 0.9f, 0.5f,   // y = 0
             1.0f, 0.1f, 0.3f};  // y = 1
  plane.origin_x = 1.5;
  plane.origin_y = -2;
  plane.resolution = 0.5;
  const std::string prefix = (dir_ / "region").string();
  ASSERT_TRUE(WriteRegionFiles(prefix, plane, MapMode::kTrinary).ok());
  absl::StatusOr<Snapshot> snapshot = ReadSnapshot(prefix + ".yaml");
  ASSERT_TRUE(snapshot.ok()) << snapshot.status();
  EXPECT_EQ(snapshot->metadata.image, "region.pgm");
  EXPECT_EQ(snapshot->metadata.origin_x, 1.5);
  uint32_t ox, oy;
  ASSERT_TRUE(PlaceSnapshot(*snapshot, {0.5, 1.5, -2, 3, 2}, "region", ox, oy).ok());
  const std::vector<CellBatch> batches = SnapshotBatches(*snapshot, 0, ox, oy, 100);
  ASSERT_EQ(batches.size(), 1u);
  // Known cells in image order (top row first): (0,1)=1, (1,1)=0, (0,0)=0, (1,0)=1. 0.5 and 0.3
  // are unknown.
  EXPECT_EQ(batches[0].x, (std::vector<uint32_t>{0, 1, 0, 1}));
  EXPECT_EQ(batches[0].y, (std::vector<uint32_t>{1, 1, 0, 0}));
  EXPECT_EQ(batches[0].values, (std::vector<float>{1, 0, 0, 1}));
  absl::StatusOr<Image> png = ReadPng(prefix + ".png");
  ASSERT_TRUE(png.ok()) << png.status();
  EXPECT_EQ(png->at(0, 0), 0);    // p = 1 at (0, 1): black
  EXPECT_EQ(png->at(2, 1), 128);  // p = 0.5 at (2, 0)
  EXPECT_EQ(png->at(0, 1), 255);  // p = 0 at (0, 0): white
}

}  // namespace
}  // namespace fremen::formats
