#include "client/formats/png.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <zlib.h>

#include "client/formats/png_decode.h"

namespace fremen::formats {
namespace {

using ::testing::HasSubstr;

Image Gradient(int width, int height, int channels) {
  Image image(width, height, channels);
  for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<uint8_t>(i * 7 + i / 13);
  return image;
}

TEST(PngTest, GrayscaleDecodesBackToTheSamePixels) {
  const Image image = Gradient(37, 11, 1);
  absl::StatusOr<std::string> png = EncodePng(image);
  ASSERT_TRUE(png.ok()) << png.status();
  absl::StatusOr<Image> decoded = DecodePng(*png);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(decoded->width, 37);
  EXPECT_EQ(decoded->height, 11);
  EXPECT_EQ(decoded->channels, 1);
  EXPECT_EQ(decoded->pixels, image.pixels);
}

TEST(PngTest, RgbDecodesBackToTheSamePixels) {
  const Image image = Gradient(5, 9, 3);
  absl::StatusOr<std::string> png = EncodePng(image);
  ASSERT_TRUE(png.ok()) << png.status();
  absl::StatusOr<Image> decoded = DecodePng(*png);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(decoded->channels, 3);
  EXPECT_EQ(decoded->pixels, image.pixels);
}

TEST(PngTest, TheFileIsSignatureThenIhdrIdatIend) {
  absl::StatusOr<std::string> png = EncodePng(Gradient(4, 4, 1));
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png->substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(png->substr(12, 4), "IHDR");
  EXPECT_EQ(png->substr(8 + 25 + 4, 4), "IDAT");
  EXPECT_EQ(png->substr(png->size() - 8, 4), "IEND");
}

TEST(PngTest, DecoderChecksCrcs) {
  absl::StatusOr<std::string> png = EncodePng(Gradient(4, 4, 1));
  ASSERT_TRUE(png.ok());
  std::string corrupt = *png;
  corrupt[20] ^= 1;  // inside IHDR's data
  EXPECT_THAT(DecodePng(corrupt).status().message(), HasSubstr("CRC mismatch in chunk IHDR"));
  EXPECT_THAT(DecodePng("GIF89a").status().message(), HasSubstr("bad signature"));
}

TEST(PngTest, DecoderUndoesEveryRowFilter) {
  // Rows filtered with Sub, Up, Average and Paeth by hand: a 2 × 4 gray image.
  const uint8_t pixels[4][2] = {{10, 20}, {30, 50}, {70, 71}, {5, 250}};
  std::string raw;
  raw += std::string{1, 10, static_cast<char>(20 - 10)};                                         // Sub
  raw += std::string{2, static_cast<char>(30 - 10), static_cast<char>(50 - 20)};                 // Up
  raw += std::string{3, static_cast<char>(70 - 30 / 2), static_cast<char>(71 - (70 + 50) / 2)};  // Average
  // Paeth row 3: first byte predictor = b (above 70); second: a=5, b=71, c=70 → p=6, nearest a.
  raw += std::string{4, static_cast<char>(5 - 70), static_cast<char>(250 - 5)};
  uLongf size = compressBound(raw.size());
  std::string idat(size, '\0');
  ASSERT_EQ(
      compress(reinterpret_cast<Bytef*>(idat.data()), &size, reinterpret_cast<const Bytef*>(raw.data()), raw.size()),
      Z_OK);
  idat.resize(size);
  // Reuse the encoder's framing: encode an image of the same size, then swap its IDAT.
  absl::StatusOr<std::string> frame = EncodePng(Image(2, 4, 1));
  ASSERT_TRUE(frame.ok());
  const std::string head = frame->substr(0, 8 + 25);
  std::string chunk;
  const auto put32 = [&](uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) chunk.push_back(static_cast<char>(v >> shift));
  };
  put32(static_cast<uint32_t>(idat.size()));
  chunk += "IDAT" + idat;
  put32(static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(chunk.data() + 4), chunk.size() - 4)));
  absl::StatusOr<Image> decoded = DecodePng(head + chunk + frame->substr(frame->size() - 12));
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 2; ++x) EXPECT_EQ(decoded->at(x, y), pixels[y][x]) << x << "," << y;
  }
}

TEST(PngTest, RefusesBadImages) {
  EXPECT_THAT(EncodePng(Image(2, 2, 2)).status().message(), HasSubstr("channels must be 1 or 3"));
  EXPECT_FALSE(EncodePng(Image()).ok());
}

}  // namespace
}  // namespace fremen::formats
