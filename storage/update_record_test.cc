#include "storage/update_record.h"

#include <gtest/gtest.h>

#include <fstream>

#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

UpdateRecord Sample() {
  UpdateRecord r;
  r.start_time = 1.7e9 + 0.25;
  r.duration_seconds = 0.61;
  r.states_updated = 1'000'000;
  r.prediction_error_before = 0.213;
  r.prediction_error_after = 0.177;
  r.order_histogram = {10, 0, 3, 999'987, 0, 0};
  return r;
}

TEST(UpdateRecordTest, RoundTripsThroughItsFile) {
  fremen::testing::TempDir dir;
  const std::string path = dir.path() + "/last_update";
  auto missing = ReadUpdateRecord(Env::Default(), path);
  ASSERT_TRUE(missing.ok()) << missing.status();
  EXPECT_FALSE(missing->has_value());
  ASSERT_TRUE(WriteUpdateRecord(Env::Default(), path, Sample()).ok());
  UpdateRecord second = Sample();
  second.states_updated = 0;
  ASSERT_TRUE(WriteUpdateRecord(Env::Default(), path, second).ok());  // replaces the first
  auto read = ReadUpdateRecord(Env::Default(), path);
  ASSERT_TRUE(read.ok()) << read.status();
  ASSERT_TRUE(read->has_value());
  EXPECT_EQ(**read, second);
}

TEST(UpdateRecordTest, CorruptBytesAreDataLossNamingTheField) {
  const std::string bytes = EncodeUpdateRecord(Sample());
  for (size_t cut = 0; cut < bytes.size(); ++cut) {
    EXPECT_TRUE(absl::IsDataLoss(DecodeUpdateRecord(bytes.substr(0, cut)).status())) << "cut at " << cut;
  }
  std::string version = bytes;
  version[0] = 9;
  EXPECT_NE(DecodeUpdateRecord(version).status().message().find("version"), std::string::npos);
  EXPECT_TRUE(absl::IsDataLoss(DecodeUpdateRecord(bytes + "x").status())) << "trailing bytes";
}

}  // namespace
}  // namespace fremen::storage
