#include "storage/env/fault_injection_env.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>

#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

std::span<const uint8_t> Bytes(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

bool Listed(Env& env, const std::string& dir, const std::string& name) {
  auto names = env.ListDir(dir);
  return names.ok() && std::find(names->begin(), names->end(), name) != names->end();
}

TEST(FaultInjectionEnvTest, APowerCutKeepsWhatWasSyncedAndNothingElse) {
  fremen::testing::TempDir dir;
  const std::string durable = dir.path() + "/durable", fresh = dir.path() + "/fresh";
  FaultInjectionEnv env;
  auto file = env.NewWritableFile(durable);
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_TRUE((*file)->Append(Bytes("synced ")).ok());
  ASSERT_TRUE((*file)->Sync().ok());
  ASSERT_TRUE(env.SyncDir(dir.path()).ok());
  ASSERT_TRUE((*file)->Append(Bytes("lost")).ok());
  auto other = env.NewWritableFile(fresh);  // its directory is never synced
  ASSERT_TRUE(other.ok());
  ASSERT_TRUE((*other)->Append(Bytes("x")).ok());
  ASSERT_TRUE((*other)->Sync().ok());
  env.CutPower();
  EXPECT_TRUE(absl::IsUnavailable(env.ReadFile(durable).status())) << "a cut machine does nothing";
  EXPECT_FALSE((*file)->Append(Bytes("after")).ok());
  env.PowerOn();
  auto read = env.ReadFile(durable);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(*read, "synced ");
  EXPECT_TRUE(absl::IsNotFound(env.ReadFile(fresh).status()));
}

TEST(FaultInjectionEnvTest, UnlinksAndRenamesNotDirSyncedAreUndone) {
  fremen::testing::TempDir dir;
  const std::string a = dir.path() + "/a", b = dir.path() + "/b";
  FaultInjectionEnv env;
  ASSERT_TRUE(WriteFileAtomically(&env, a, "old a").ok());
  ASSERT_TRUE(WriteFileAtomically(&env, b, "old b").ok());
  ASSERT_TRUE(env.Unlink(a).ok());
  EXPECT_FALSE(Listed(env, dir.path(), "a"));
  EXPECT_EQ(env.ListDir(dir.path())->size(), 1u) << "the file moved aside is hidden";
  auto tmp = env.NewWritableFile(b + ".new");
  ASSERT_TRUE(tmp.ok());
  ASSERT_TRUE((*tmp)->Append(Bytes("new b")).ok());
  ASSERT_TRUE((*tmp)->Sync().ok());
  ASSERT_TRUE(env.Rename(b + ".new", b).ok());
  EXPECT_EQ(*env.ReadFile(b), "new b");
  env.CutPower();
  env.PowerOn();
  EXPECT_EQ(*env.ReadFile(a), "old a");
  EXPECT_EQ(*env.ReadFile(b), "old b");
  EXPECT_FALSE(Listed(env, dir.path(), "b.new"));
  // Once the directory is synced, they hold.
  ASSERT_TRUE(env.Unlink(a).ok());
  ASSERT_TRUE(WriteFileAtomically(&env, b, "newer b").ok());
  env.CutPower();
  env.PowerOn();
  EXPECT_TRUE(absl::IsNotFound(env.ReadFile(a).status()));
  EXPECT_EQ(*env.ReadFile(b), "newer b");
}

TEST(FaultInjectionEnvTest, FaultsOnDemandAndCutsAfterCountedOperations) {
  fremen::testing::TempDir dir;
  const std::string path = dir.path() + "/f";
  FaultInjectionEnv env(7);
  auto file = env.NewWritableFile(path);
  ASSERT_TRUE(file.ok());
  ASSERT_TRUE(env.SyncDir(dir.path()).ok());
  env.FailWrites(ENOSPC);
  const absl::Status full = (*file)->Append(Bytes("abc"));
  EXPECT_TRUE(absl::IsResourceExhausted(full)) << full;
  EXPECT_EQ(*env.FileSize(path), 0u) << "a refused write writes nothing";
  env.FailWrites(0);
  env.FailSyncs(EIO);
  ASSERT_TRUE((*file)->Append(Bytes("abc")).ok());
  EXPECT_NE((*file)->Sync().message().find("Input/output error"), std::string::npos);
  env.FailSyncs(0);
  env.TearNextWrite();
  EXPECT_FALSE((*file)->Append(Bytes("0123456789")).ok());
  const uint64_t torn = *env.FileSize(path) - 3;
  EXPECT_GE(torn, 1u);
  EXPECT_LT(torn, 10u);
  env.CutPowerAfter(2);
  EXPECT_TRUE((*file)->Append(Bytes("x")).ok());
  EXPECT_FALSE((*file)->Sync().ok());  // the second operation: the power goes before it
  EXPECT_TRUE(env.power_cut());
  env.PowerOn();
  EXPECT_EQ(*env.FileSize(path), 0u) << "nothing was ever synced";
}

}  // namespace
}  // namespace fremen::storage
