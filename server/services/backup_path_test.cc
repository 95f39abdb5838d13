// Backup directories stay inside the backup root: relative paths are joined and normalised;
// empty, absolute, ".." and links out of the root are refused, naming the field.
#include "server/services/backup_path.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

TEST(BackupPathTest, JoinsAndNormalises) {
  EXPECT_EQ(*ResolveBackupPath("/var/backups/fremen", "nightly/lab", "directory"), "/var/backups/fremen/nightly/lab");
  EXPECT_EQ(*ResolveBackupPath("/var/backups/fremen/", "./a//b/", "directory"), "/var/backups/fremen/a/b");
  EXPECT_EQ(*ResolveBackupPath("/var/backups/fremen", "a/./b/.", "directory"), "/var/backups/fremen/a/b");
  EXPECT_EQ(*ResolveBackupPath("/b", "lab..2024", "directory"), "/b/lab..2024");  // dots inside a name are fine
}

TEST(BackupPathTest, RefusesPathsOutsideTheRoot) {
  for (const char* bad : {"/etc", "/", "..", "../x", "a/../../x", "a/..", ".", "./"}) {
    const absl::Status s = ResolveBackupPath("/var/backups/fremen", bad, "directory").status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(std::string(s.message()), HasSubstr("directory")) << bad;
  }
  const absl::Status empty = ResolveBackupPath("/b", "", "directory").status();
  EXPECT_EQ(empty.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(empty.message(), "directory is required");
  EXPECT_THAT(std::string(ResolveBackupPath("/b", "/etc", "directory").status().message()), HasSubstr("absolute"));
  EXPECT_THAT(std::string(ResolveBackupPath("/b", "a/../..", "directory").status().message()), HasSubstr(".."));
  EXPECT_EQ(ResolveBackupPath("/b", std::string("a\0b", 3), "directory").status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(BackupPathTest, RefusesALinkOutOfTheRoot) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("fremen-backup-path-" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "backups");
  fs::create_directories(root / "elsewhere");
  fs::create_directory_symlink(root / "elsewhere", root / "backups" / "escape");
  fs::create_directory_symlink(root / "backups" / "inside", root / "backups" / "alias");
  const std::string backups = (root / "backups").string();
  const absl::Status escaped = ResolveBackupPath(backups, "escape/lab", "directory").status();
  EXPECT_EQ(escaped.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(escaped.message()), HasSubstr("symbolic link"));
  EXPECT_TRUE(ResolveBackupPath(backups, "alias/lab", "directory").ok());  // a link that stays inside
  fs::remove_all(root);
}

}  // namespace
}  // namespace fremen::server
