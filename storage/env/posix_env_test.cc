// The real file system's Env: ReadFile returns a file's bytes exactly, whatever its size says.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <string>

#include "absl/strings/str_cat.h"
#include "storage/env/env.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

std::string WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

TEST(PosixEnvTest, ReadFileReturnsEveryByteOfFilesOfAnySize) {
  fremen::testing::TempDir dir;
  std::mt19937_64 rng(7);
  // Empty, under one read, and several MB with an odd tail (a log segment's shape).
  for (size_t size : {size_t{0}, size_t{100}, size_t{(3 << 20) + 3}}) {
    std::string bytes(size, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    const std::string path = WriteFile(dir.Path(absl::StrCat("f", size)), bytes);
    auto read = Env::Default()->ReadFile(path);
    ASSERT_TRUE(read.ok()) << read.status();
    EXPECT_EQ(read->size(), size);
    EXPECT_TRUE(*read == bytes) << size;
  }
}

// A file whose size stat() does not know (/proc's are 0) is read to its end all the same.
TEST(PosixEnvTest, ReadFileReadsPastTheSizeTheFileSystemReports) {
  auto read = Env::Default()->ReadFile("/proc/self/status");
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_NE(read->find("Pid:"), std::string::npos) << *read;
}

TEST(PosixEnvTest, ReadFileOfAMissingFileIsNotFoundNamingIt) {
  fremen::testing::TempDir dir;
  auto read = Env::Default()->ReadFile(dir.Path("missing"));
  EXPECT_TRUE(absl::IsNotFound(read.status())) << read.status();
  EXPECT_NE(read.status().message().find("missing"), std::string::npos) << read.status();
}

}  // namespace
}  // namespace fremen::storage
