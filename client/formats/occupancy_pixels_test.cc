#include "client/formats/occupancy_pixels.h"

#include <gtest/gtest.h>

namespace fremen::formats {
namespace {

MapMetadata Trinary(double occupied, double free) {
  MapMetadata m;
  m.occupied_thresh = occupied;
  m.free_thresh = free;
  return m;
}

TEST(OccupancyPixelsTest, OccupancyIsInvertedBrightnessUnlessNegate) {
  EXPECT_DOUBLE_EQ(PixelOccupancy(0, false), 1.0);
  EXPECT_DOUBLE_EQ(PixelOccupancy(255, false), 0.0);
  EXPECT_DOUBLE_EQ(PixelOccupancy(205, false), 50.0 / 255);
  EXPECT_DOUBLE_EQ(PixelOccupancy(205, true), 205.0 / 255);
}

TEST(OccupancyPixelsTest, TrinaryThresholdsAsMapServer) {
  const MapMetadata ros1 = Trinary(0.65, 0.196);
  EXPECT_EQ(CellFromPixel(kPixelOccupied, ros1), kCellOccupied);
  EXPECT_EQ(CellFromPixel(kPixelFree, ros1), kCellFree);
  EXPECT_EQ(CellFromPixel(kPixelUnknown, ros1), kCellUnknown);  // 0.19608 is not < 0.196
  // nav2's default free threshold reads 205 as free: its own rule, kept.
  EXPECT_EQ(CellFromPixel(kPixelUnknown, Trinary(0.65, 0.25)), kCellFree);
  // Around a threshold: occ(100) = 0.608 > 0.6, occ(104) = 0.592.
  EXPECT_EQ(CellFromPixel(100, Trinary(0.6, 0.2)), kCellOccupied);
  EXPECT_EQ(CellFromPixel(104, Trinary(0.6, 0.2)), kCellUnknown);
  MapMetadata negated = ros1;
  negated.negate = true;
  EXPECT_EQ(CellFromPixel(255, negated), kCellOccupied);
  EXPECT_EQ(CellFromPixel(0, negated), kCellFree);
}

TEST(OccupancyPixelsTest, ScaleModeIsLinearBetweenTheThresholds) {
  MapMetadata m = Trinary(0.65, 0.25);
  m.mode = MapMode::kScale;
  // occ = 0.45 is halfway between 0.25 and 0.65: 50. 255 · 0.55 = 140.25, so pixel 140 gives
  // occ = 115/255 = 0.45098 → rint(50.245) = 50.
  EXPECT_EQ(CellFromPixel(140, m), 50);
  EXPECT_FLOAT_EQ(*ObservationFromPixel(140, m), 0.5f);
  EXPECT_EQ(CellFromPixel(0, m), kCellOccupied);
  EXPECT_EQ(CellFromPixel(255, m), kCellFree);
}

TEST(OccupancyPixelsTest, ObservationsSkipUnknownCells) {
  const MapMetadata m = Trinary(0.65, 0.196);
  EXPECT_EQ(ObservationFromPixel(kPixelOccupied, m), 1.0f);
  EXPECT_EQ(ObservationFromPixel(kPixelFree, m), 0.0f);
  EXPECT_FALSE(ObservationFromPixel(kPixelUnknown, m).has_value());
}

TEST(OccupancyPixelsTest, ExportWritesMapSaverPixelsThatReadBackTheSame) {
  const MapMetadata m = Trinary(kExportOccupiedThresh, kExportFreeThresh);
  EXPECT_EQ(PixelFromProbability(1.0, m), kPixelOccupied);
  EXPECT_EQ(PixelFromProbability(0.65, m), kPixelOccupied);  // cell 65 ≥ 65
  EXPECT_EQ(PixelFromProbability(0.64, m), kPixelUnknown);
  EXPECT_EQ(PixelFromProbability(0.5, m), kPixelUnknown);  // never observed
  EXPECT_EQ(PixelFromProbability(0.2, m), kPixelFree);     // cell 20 ≤ rint(19.6)
  EXPECT_EQ(PixelFromProbability(0.0, m), kPixelFree);
  EXPECT_EQ(PixelFromProbability(-3, m), kPixelFree);  // clamped
  for (double p : {0.0, 0.1, 0.5, 0.9, 1.0}) {
    const int cell = CellFromPixel(PixelFromProbability(p, m), m);
    EXPECT_EQ(cell, p >= 0.65 ? kCellOccupied : p <= 0.2 ? kCellFree : kCellUnknown) << p;
  }
  MapMetadata scale = m;
  scale.mode = MapMode::kScale;
  EXPECT_EQ(PixelFromProbability(1.0, scale), 0);
  EXPECT_EQ(PixelFromProbability(0.0, scale), 255);
  EXPECT_EQ(PixelFromProbability(0.5, scale), 128);  // lround(127.5)
}

}  // namespace
}  // namespace fremen::formats
