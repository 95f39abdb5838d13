// The C++ client's examples (client/examples) run against a real fremend, so that they stay
// working, not only compiling: ingest two weeks and predict the door, then export the map as PGM.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include "absl/strings/str_cat.h"
#include "tests/fremend_fixture.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

// Runs `command` with the shell; its stdout and exit code.
std::pair<int, std::string> Shell(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, out};
  char buffer[4096];
  for (size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

class ClientExamplesTest : public DaemonTest {};

TEST_F(ClientExamplesTest, IngestAndPredictThenExportRegion) {
  auto [code, out] = Shell(absl::StrCat("'", INGEST_AND_PREDICT_BINARY, "' ", daemon_->address(), " 2>&1"));
  ASSERT_EQ(code, 0) << out;
  EXPECT_THAT(out, HasSubstr("week 2: 168 scans, 336 observations accepted, 0 rejected"));
  // The door is open (free) at noon and closed at midnight.
  EXPECT_THAT(out, HasSubstr("door cell occupied: p = 0.00 at noon, 1.00 at midnight"));

  const std::string pgm = dir_.Path("floor.pgm");
  auto [export_code, export_out] = Shell(
      absl::StrCat("'", EXPORT_REGION_BINARY, "' example-floor 1700000000 '", pgm, "' ", daemon_->address(), " 2>&1"));
  ASSERT_EQ(export_code, 0) << export_out;
  std::ifstream in(pgm, std::ios::binary);
  const std::string image((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = "P5\n40 20\n255\n";
  ASSERT_EQ(image.substr(0, header.size()), header);
  EXPECT_EQ(image.size(), header.size() + 40 * 20);
}

}  // namespace
}  // namespace fremen::testing
