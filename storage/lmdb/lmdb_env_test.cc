#include "storage/lmdb/lmdb_env.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <thread>
#include <vector>

#include "storage/testing/temp_dir.h"

namespace fremen::storage {
namespace {

LmdbOptions Cells() {
  LmdbOptions options;
  options.databases = {"cells"};
  return options;
}

std::vector<uint8_t> Key(uint64_t i) {
  std::vector<uint8_t> k(8);
  for (int b = 0; b < 8; ++b) k[b] = static_cast<uint8_t>(i >> (56 - 8 * b));  // big-endian: sorted
  return k;
}

TEST(LmdbEnvTest, GrowsTheMapInsteadOfFailingWrites) {
  testing::TempDir dir;
  LmdbOptions options = Cells();
  options.initial_map_size = 64 << 10;  // 64 KiB: full after a few pages
  auto env = LmdbEnv::Open(dir.path(), options);
  ASSERT_TRUE(env.ok()) << env.status();
  const std::vector<uint8_t> value(1000, 0xAB);
  for (int round = 0; round < 10; ++round) {
    ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status {
      auto dbi = txn.Db("cells");
      if (!dbi.ok()) return dbi.status();
      for (uint64_t i = 0; i < 1000; ++i) {
        if (auto s = txn.Put(*dbi, Key(round * 1000 + i), value); !s.ok()) return s;
      }
      return absl::OkStatus();
    }).ok());
  }
  EXPECT_GT((*env)->map_size(), 10u * 1000 * 1000);
  size_t count = 0;
  ASSERT_TRUE((*env)->Read([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    if (!dbi.ok()) return dbi.status();
    auto n = txn.Count(*dbi);
    if (!n.ok()) return n.status();
    count = *n;
    return absl::OkStatus();
  }).ok());
  EXPECT_EQ(count, 10000u);
}

TEST(LmdbEnvTest, ScanVisitsAKeyRangeInOrder) {
  testing::TempDir dir;
  auto env = LmdbEnv::Open(dir.path(), Cells());
  ASSERT_TRUE(env.ok());
  ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    for (uint64_t i = 0; i < 100; ++i) {
      if (auto s = txn.Put(*dbi, Key(i * 10), Key(i)); !s.ok()) return s;
    }
    return absl::OkStatus();
  }).ok());
  std::vector<uint64_t> seen;
  ASSERT_TRUE((*env)->Read([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    return txn.Scan(*dbi, Key(205), Key(300), [&](auto, std::span<const uint8_t> v) {
      seen.push_back(v[7]);
      return true;
    });
  }).ok());
  EXPECT_EQ(seen, (std::vector<uint64_t>{21, 22, 23, 24, 25, 26, 27, 28, 29}));
}

TEST(LmdbEnvTest, AFailingTransactionLeavesNothingBehind) {
  testing::TempDir dir;
  auto env = LmdbEnv::Open(dir.path(), Cells());
  ASSERT_TRUE(env.ok());
  const absl::Status failed = (*env)->Write([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    if (auto s = txn.Put(*dbi, Key(1), Key(1)); !s.ok()) return s;
    return absl::InvalidArgumentError("changed my mind");
  });
  EXPECT_TRUE(absl::IsInvalidArgument(failed));
  EXPECT_TRUE((*env)->health().ok());  // a caller's error is not a storage failure
  const absl::Status read = (*env)->Read([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    if (!dbi.ok()) return dbi.status();
    return txn.Get(*dbi, Key(1)).status();
  });
  EXPECT_TRUE(absl::IsNotFound(read)) << read;
}

TEST(LmdbEnvTest, ReadersRunConcurrentlyWithAGrowingWriter) {
  testing::TempDir dir;
  LmdbOptions options = Cells();
  options.initial_map_size = 64 << 10;
  auto env = LmdbEnv::Open(dir.path(), options);
  ASSERT_TRUE(env.ok());
  std::atomic<bool> done = false;
  std::atomic<size_t> last_seen = 0;
  std::thread reader([&] {
    while (!done) {
      (void)(*env)->Read([&](LmdbTxn& txn) -> absl::Status {
        auto dbi = txn.Db("cells");
        if (!dbi.ok()) return dbi.status();
        auto n = txn.Count(*dbi);
        if (n.ok()) {
          EXPECT_GE(*n, last_seen.load());  // snapshots never go back in time
          last_seen = *n;
        }
        return absl::OkStatus();
      });
    }
  });
  const std::vector<uint8_t> value(500, 1);
  for (uint64_t i = 0; i < 200; ++i) {
    ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status {
      auto dbi = txn.Db("cells");
      for (uint64_t j = 0; j < 50; ++j) {
        if (auto s = txn.Put(*dbi, Key(i * 50 + j), value); !s.ok()) return s;
      }
      return absl::OkStatus();
    }).ok());
  }
  done = true;
  reader.join();
  EXPECT_LE(last_seen.load(), 10000u);
}

TEST(LmdbEnvTest, CopyIsAConsistentEnvironment) {
  testing::TempDir dir;
  auto env = LmdbEnv::Open(dir.path() + "/a", Cells());
  ASSERT_TRUE(env.ok());
  ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    return txn.Put(*dbi, Key(7), Key(42));
  }).ok());
  ASSERT_TRUE((*env)->CopyTo(dir.path() + "/b").ok());
  auto copy = LmdbEnv::Open(dir.path() + "/b", Cells());
  ASSERT_TRUE(copy.ok());
  ASSERT_TRUE((*copy)->Read([&](LmdbTxn& txn) -> absl::Status {
    auto dbi = txn.Db("cells");
    auto v = txn.Get(*dbi, Key(7));
    if (!v.ok()) return v.status();
    EXPECT_EQ((*v)[7], 42);
    return absl::OkStatus();
  }).ok());
}

TEST(LmdbEnvTest, OpeningAGarbageFileIsAnErrorNotACrash) {
  testing::TempDir dir;
  {
    std::FILE* f = std::fopen((dir.path() + "/data.mdb").c_str(), "wb");
    std::vector<char> junk(8192, 'x');
    std::fwrite(junk.data(), 1, junk.size(), f);
    std::fclose(f);
  }
  auto env = LmdbEnv::Open(dir.path(), Cells());
  EXPECT_FALSE(env.ok());
}

}  // namespace
}  // namespace fremen::storage
