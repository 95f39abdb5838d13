#include "server/gateway/region_png.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace fremen::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

v1::PredictRegionRequest Request(const std::multimap<std::string, std::string>& params) {
  auto request = RegionPngRequest(params);
  EXPECT_TRUE(request.ok()) << request.status();
  return request.ok() ? *request : v1::PredictRegionRequest();
}

TEST(RegionPngTest, ModesChooseTheOutput) {
  EXPECT_EQ(Request({}).output(), v1::REGION_OUTPUT_FLOAT);
  EXPECT_EQ(Request({{"mode", "probability"}}).output(), v1::REGION_OUTPUT_FLOAT);
  EXPECT_EQ(Request({{"mode", "entropy"}}).output(), v1::REGION_OUTPUT_ENTROPY);
  const v1::PredictRegionRequest state = Request({{"mode", "state"}, {"confidence", "0.7"}, {"hi.x", "3"}});
  EXPECT_EQ(state.output(), v1::REGION_OUTPUT_STATES);
  EXPECT_FLOAT_EQ(state.confidence(), 0.7f);
  EXPECT_EQ(state.hi().x(), 3u);
}

TEST(RegionPngTest, BadParametersAreNamed) {
  EXPECT_THAT(RegionPngRequest({{"mode", "heat"}}).status().message(),
              HasSubstr("query parameter mode: must be probability, entropy or state, got \"heat\""));
  EXPECT_THAT(RegionPngRequest({{"output", "REGION_OUTPUT_UINT8"}}).status().message(), HasSubstr("query parameter output"));
  EXPECT_THAT(RegionPngRequest({{"lo.z", "0"}, {"hi.z", "2"}}).status().message(), HasSubstr("one z-plane"));
  EXPECT_THAT(RegionPngRequest({{"bogus", "1"}}).status().message(), HasSubstr("unknown query parameter: bogus"));
  EXPECT_TRUE(RegionPngRequest({{"lo.z", "2"}, {"hi.z", "3"}}).ok());
}

TEST(RegionPngTest, RowZeroIsTheHighestYAndGrayIsOneMinusP) {
  v1::PredictRegionRequest request = Request({{"lo.x", "1"}, {"hi.x", "3"}, {"lo.y", "0"}, {"hi.y", "2"}});
  v1::PredictRegionResponse region;
  for (float p : {0.0f, 1.0f, 0.5f, 0.25f}) region.add_float_values(p);  // (1,0) (2,0) (1,1) (2,1)
  auto pixels = RegionPngPixels(request, region);
  ASSERT_TRUE(pixels.ok()) << pixels.status();
  EXPECT_THAT(*pixels, ElementsAre(128, 191, 255, 0));  // the y = 1 row first
}

TEST(RegionPngTest, StatesAreBlackOrWhite) {
  v1::PredictRegionRequest request = Request({{"mode", "state"}, {"hi.x", "3"}, {"hi.y", "1"}});
  v1::PredictRegionResponse region;
  region.set_bytes_values(std::string("\x01\x00\x01", 3));
  auto pixels = RegionPngPixels(request, region);
  ASSERT_TRUE(pixels.ok()) << pixels.status();
  EXPECT_THAT(*pixels, ElementsAre(0, 255, 0));
}

TEST(RegionPngTest, TheFileIsAPngOfTheBoxSize) {
  v1::PredictRegionRequest request = Request({{"hi.x", "300"}, {"hi.y", "2"}});
  v1::PredictRegionResponse region;
  for (int i = 0; i < 600; ++i) region.add_float_values(static_cast<float>(i % 2));
  auto png = RegionPng(request, region);
  ASSERT_TRUE(png.ok()) << png.status();
  ASSERT_GT(png->size(), 24u);
  EXPECT_EQ(png->substr(0, 8), "\x89PNG\r\n\x1a\n");
  const auto be32 = [&](size_t at) {
    return (uint32_t{static_cast<uint8_t>((*png)[at])} << 24) | (uint32_t{static_cast<uint8_t>((*png)[at + 1])} << 16) |
           (uint32_t{static_cast<uint8_t>((*png)[at + 2])} << 8) | uint32_t{static_cast<uint8_t>((*png)[at + 3])};
  };
  EXPECT_EQ(png->substr(12, 4), "IHDR");
  EXPECT_EQ(be32(16), 300u);  // width
  EXPECT_EQ(be32(20), 2u);    // height
}

TEST(RegionPngTest, AnAnswerOfAnotherSizeIsRefused) {
  v1::PredictRegionRequest request = Request({{"hi.x", "2"}, {"hi.y", "2"}});
  v1::PredictRegionResponse region;
  region.add_float_values(0.5f);
  EXPECT_THAT(RegionPngPixels(request, region).status().message(), HasSubstr("holds 1 values, not the 2 × 2"));
}

}  // namespace
}  // namespace fremen::server
