// The C++ client's examples (client/examples) run against a real fremend, so that they stay
// working, not only compiling: ingest two weeks and predict the door, then export the map as PGM.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "tests/fremend_fixture.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

class ClientExamplesTest : public DaemonTest {};

TEST_F(ClientExamplesTest, IngestAndPredictThenExportRegion) {
  const RunResult ingest = RunProgram(INGEST_AND_PREDICT_BINARY, {daemon_->address()});
  ASSERT_EQ(ingest.exit_code, 0) << Describe(ingest) << "\n" << ingest.out << ingest.err;
  EXPECT_THAT(ingest.out, HasSubstr("week 2: 168 scans, 336 observations accepted, 0 rejected"));
  // The door is open (free) at noon and closed at midnight.
  EXPECT_THAT(ingest.out, HasSubstr("door cell occupied: p = 0.00 at noon, 1.00 at midnight"));
  EXPECT_EQ(ingest.err, "");

  const std::string pgm = dir_.Path("floor.pgm");
  const RunResult exported =
      RunProgram(EXPORT_REGION_BINARY, {"example-floor", "1700000000", pgm, daemon_->address()});
  ASSERT_EQ(exported.exit_code, 0) << Describe(exported) << "\n" << exported.out << exported.err;
  EXPECT_EQ(exported.err, "");
  std::ifstream in(pgm, std::ios::binary);
  const std::string image((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = "P5\n40 20\n255\n";
  ASSERT_EQ(image.substr(0, header.size()), header);
  EXPECT_EQ(image.size(), header.size() + 40 * 20);
}

}  // namespace
}  // namespace fremen::testing
