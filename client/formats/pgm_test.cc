#include "client/formats/pgm.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace fremen::formats {
namespace {

using ::testing::HasSubstr;

TEST(PgmTest, BinaryRoundTrip) {
  Image image(3, 2, 1);
  image.pixels = {0, 205, 254, 10, 20, 255};
  const std::string path = (std::filesystem::temp_directory_path() / "fremen_pgm_test.pgm").string();
  ASSERT_TRUE(WritePgm(path, image).ok());
  absl::StatusOr<Image> read = ReadPgm(path);
  std::remove(path.c_str());
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->width, 3);
  EXPECT_EQ(read->height, 2);
  EXPECT_EQ(read->pixels, image.pixels);
}

TEST(PgmTest, AsciiWithCommentsAndOtherMaxval) {
  // maxval 15: 15 is white (255), 0 black, 5 → 85.
  absl::StatusOr<Image> image = ParsePgm("P2\n# a comment\n2 2 # size\n15\n0 5\n15 10\n", "a.pgm");
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->pixels, (std::vector<uint8_t>{0, 85, 255, 170}));
}

TEST(PgmTest, BinaryHeaderCommentBeforeData) {
  std::string bytes = "P5\n# CREATOR: map_saver\n2 1\n255\n";
  bytes += std::string("\x00\xfe", 2);
  absl::StatusOr<Image> image = ParsePgm(bytes, "m.pgm");
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->pixels, (std::vector<uint8_t>{0, 254}));
}

TEST(PgmTest, ErrorsNameTheFileAndTheProblem) {
  EXPECT_THAT(ParsePgm("P6\n1 1\n255\nabc", "c.ppm").status().message(), HasSubstr("c.ppm: not a PGM file"));
  EXPECT_THAT(ParsePgm("P5\n4 4\n255\nab", "t.pgm").status().message(), HasSubstr("t.pgm: truncated PGM data"));
  // A header claiming a huge image is refused before anything is allocated.
  EXPECT_THAT(ParsePgm("P5\n100000 100000\n255\nab", "h.pgm").status().message(), HasSubstr("truncated PGM data"));
  EXPECT_THAT(ParsePgm("P5\n0 4\n255\n", "w.pgm").status().message(), HasSubstr("width"));
  EXPECT_THAT(ParsePgm("P2\n2 1\n255\n7\n", "p2.pgm").status().message(), HasSubstr("expected 2 pixel values, read 1"));
  EXPECT_THAT(ParsePgm("P2\n1 1\n10\n11\n", "m.pgm").status().message(), HasSubstr("above maxval 10"));
  EXPECT_THAT(ReadPgm("/nonexistent/x.pgm").status().message(), HasSubstr("/nonexistent/x.pgm: cannot open"));
}

}  // namespace
}  // namespace fremen::formats
