#include "storage/lmdb/lmdb_env.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <thread>
#include <vector>

#include "absl/strings/escaping.h"
#include "storage/testing/file_damage.h"
#include "testing/temp_dir.h"

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
  fremen::testing::TempDir dir;
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
  fremen::testing::TempDir dir;
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
  fremen::testing::TempDir dir;
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

// A reader that never pauses does not starve the writer's map growth (std::shared_mutex did: glibc prefers readers, and
// this test hung), and its snapshots never go back in time. The reader's findings are checked after it has joined.
TEST(LmdbEnvTest, ReadersRunConcurrentlyWithAGrowingWriter) {
  fremen::testing::TempDir dir;
  LmdbOptions options = Cells();
  options.initial_map_size = 64 << 10;
  auto env = LmdbEnv::Open(dir.path(), options);
  ASSERT_TRUE(env.ok());
  std::atomic<bool> done = false, first_read = false;
  size_t reads = 0, went_back = 0, last_seen = 0;
  absl::Status read_error;
  std::thread reader([&] {
    while (!done) {
      const absl::Status status = (*env)->Read([&](LmdbTxn& txn) -> absl::Status {
        auto dbi = txn.Db("cells");
        if (!dbi.ok()) return dbi.status();
        auto n = txn.Count(*dbi);
        if (!n.ok()) return n.status();
        if (*n < last_seen) ++went_back;
        last_seen = *n;
        return absl::OkStatus();
      });
      if (!status.ok() && read_error.ok()) read_error = status;
      ++reads;
      first_read = true;
    }
  });
  while (!first_read) std::this_thread::yield();  // the reader is running before the writer starts
  const std::vector<uint8_t> value(500, 1);
  absl::Status write_error;
  for (uint64_t i = 0; i < 200 && write_error.ok(); ++i) {
    write_error = (*env)->Write([&](LmdbTxn& txn) -> absl::Status {
      auto dbi = txn.Db("cells");
      for (uint64_t j = 0; j < 50; ++j) {
        if (auto s = txn.Put(*dbi, Key(i * 50 + j), value); !s.ok()) return s;
      }
      return absl::OkStatus();
    });
  }
  done = true;
  reader.join();
  EXPECT_TRUE(write_error.ok()) << write_error;
  EXPECT_TRUE(read_error.ok()) << read_error;
  EXPECT_GE(reads, 1u);
  EXPECT_EQ(went_back, 0u);
  EXPECT_LE(last_seen, 10000u);
  auto used = (*env)->UsedBytes();
  ASSERT_TRUE(used.ok());
  EXPECT_GT(*used, size_t{64} << 10);  // the map grew past its initial size while being read
}

TEST(LmdbEnvTest, CopyIsAConsistentEnvironment) {
  fremen::testing::TempDir dir;
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
  fremen::testing::TempDir dir;
  {
    std::FILE* f = std::fopen((dir.path() + "/data.mdb").c_str(), "wb");
    std::vector<char> junk(8192, 'x');
    std::fwrite(junk.data(), 1, junk.size(), f);
    std::fclose(f);
  }
  auto env = LmdbEnv::Open(dir.path(), Cells());
  EXPECT_FALSE(env.ok());
}


// One record under a distinctive key and value, in a closed environment at `dir`.
void WriteOneRecord(const std::string& dir, const std::vector<uint8_t>& key, const std::vector<uint8_t>& value) {
  auto env = LmdbEnv::Open(dir, Cells());
  ASSERT_TRUE(env.ok()) << env.status();
  ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status { return txn.Put(*txn.Db("cells"), key, value); }).ok());
}

TEST(LmdbEnvTest, ValuesComeBackWithoutTheirChecksum) {
  fremen::testing::TempDir dir;
  auto env = LmdbEnv::Open(dir.path(), Cells());
  ASSERT_TRUE(env.ok());
  const std::vector<uint8_t> value = {1, 2, 3, 4, 5}, empty;
  ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status {
    if (auto s = txn.Put(*txn.Db("cells"), Key(1), value); !s.ok()) return s;
    return txn.Put(*txn.Db("cells"), Key(2), empty);
  }).ok());
  // MDB_NOOVERWRITE keeps its meaning (the catalog's unique names).
  EXPECT_TRUE(absl::IsAlreadyExists((*env)->Write([&](LmdbTxn& txn) {
    return txn.Put(*txn.Db("cells"), Key(1), empty, MDB_NOOVERWRITE);
  })));
  ASSERT_TRUE((*env)->Read([&](LmdbTxn& txn) -> absl::Status {
    auto one = txn.Get(*txn.Db("cells"), Key(1));
    EXPECT_TRUE(one.ok()) << one.status();
    if (one.ok()) {
      EXPECT_EQ(std::vector<uint8_t>(one->begin(), one->end()), value);
    }
    auto two = txn.Get(*txn.Db("cells"), Key(2));
    EXPECT_TRUE(two.ok() && two->empty());
    std::vector<size_t> sizes;
    EXPECT_TRUE(txn.Scan(*txn.Db("cells"), {}, {}, [&](auto, auto v) {
      sizes.push_back(v.size());
      return true;
    }).ok());
    EXPECT_EQ(sizes, (std::vector<size_t>{5, 0}));
    return absl::OkStatus();
  }).ok());
}

// Every single-bit flip in a record's value or checksum, and in its key, is caught: the read is
// DataLoss naming the file, the database and the key, never the damaged bytes.
TEST(LmdbEnvTest, EveryBitFlipInARecordIsDataLossNamingFileDatabaseAndKey) {
  fremen::testing::TempDir dir;
  const std::vector<uint8_t> key = Key(0x0123456789abcdefull);
  const std::vector<uint8_t> value = {'s', 'p', 'e', 'c', 't', 'r', 'u', 'm', 0x5a, 0xa5, 0x3c, 0xc3};
  WriteOneRecord(dir.path(), key, value);
  const std::string file = dir.path() + "/data.mdb";
  const std::string pristine = testing::ReadWholeFile(file);
  const size_t value_at = testing::FindUnique(pristine, value);
  const size_t key_at = testing::FindUnique(pristine, key);
  ASSERT_NE(value_at, std::string::npos);
  ASSERT_NE(key_at, std::string::npos);
  const std::string hex_key = absl::BytesToHexString(absl::string_view(reinterpret_cast<const char*>(key.data()), 8));
  // The value and its 4-byte checksum are contiguous; then the key's 8 bytes.
  std::vector<size_t> offsets;
  for (size_t i = 0; i < value.size() + 4; ++i) offsets.push_back(value_at + i);
  for (size_t i = 0; i < key.size(); ++i) offsets.push_back(key_at + i);
  int flips = 0;
  for (const size_t offset : offsets) {
    for (int bit = 0; bit < 8; ++bit) {
      testing::WriteWholeFile(file, pristine);
      testing::FlipBit(file, offset, bit);
      auto env = LmdbEnv::Open(dir.path(), Cells());
      ASSERT_TRUE(env.ok()) << env.status();
      const bool in_key = offset >= key_at && offset < key_at + key.size();
      ASSERT_TRUE((*env)->Read([&](LmdbTxn& txn) -> absl::Status {
        auto got = txn.Get(*txn.Db("cells"), key);
        if (in_key) {
          EXPECT_TRUE(absl::IsNotFound(got.status())) << got.status();  // the record no longer has that key
        } else {
          EXPECT_TRUE(absl::IsDataLoss(got.status())) << "byte " << offset << " bit " << bit << ": " << got.status();
          EXPECT_NE(got.status().message().find(file), std::string::npos) << got.status();
          EXPECT_NE(got.status().message().find("database cells, key " + hex_key), std::string::npos) << got.status();
        }
        const absl::Status scanned = txn.Scan(*txn.Db("cells"), {}, {}, [](auto, auto) { return true; });
        EXPECT_TRUE(absl::IsDataLoss(scanned)) << "byte " << offset << " bit " << bit << ": " << scanned;
        EXPECT_NE(scanned.message().find(file), std::string::npos) << scanned;
        return absl::OkStatus();
      }).ok());
      ++flips;
    }
  }
  EXPECT_EQ(flips, 8 * (12 + 4 + 8));
}

TEST(LmdbEnvTest, ScanCheckedReportsADamagedRecordAndGoesOn) {
  fremen::testing::TempDir dir;
  const std::vector<uint8_t> damaged_value = {'d', 'a', 'm', 'a', 'g', 'e', 'd', '!'};
  {
    auto env = LmdbEnv::Open(dir.path(), Cells());
    ASSERT_TRUE(env.ok());
    ASSERT_TRUE((*env)->Write([&](LmdbTxn& txn) -> absl::Status {
      for (uint64_t i = 0; i < 3; ++i) {
        if (auto s = txn.Put(*txn.Db("cells"), Key(i), i == 1 ? damaged_value : Key(100 + i)); !s.ok()) return s;
      }
      return absl::OkStatus();
    }).ok());
  }
  const std::string file = dir.path() + "/data.mdb";
  const size_t at = testing::FindUnique(testing::ReadWholeFile(file), damaged_value);
  ASSERT_NE(at, std::string::npos);
  testing::FlipBit(file, at + 3, 0);
  auto env = LmdbEnv::Open(dir.path(), Cells());
  ASSERT_TRUE(env.ok());
  std::vector<std::string> seen;
  ASSERT_TRUE((*env)->Read([&](LmdbTxn& txn) -> absl::Status {
    return txn.ScanChecked(*txn.Db("cells"), {}, {}, [&](auto, auto value) {
      seen.push_back(value.ok() ? "ok" : std::string(value.status().message()));
      return true;
    });
  }).ok());
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0], "ok");
  EXPECT_NE(seen[1].find("key 0000000000000001: checksum mismatch"), std::string::npos) << seen[1];
  EXPECT_EQ(seen[2], "ok");
}

// A file written before records had checksums is refused as such, not read as 100% damage.
TEST(LmdbEnvTest, RecordsWithoutChecksumsAreRefusedAtOpen) {
  fremen::testing::TempDir dir;
  MDB_env* raw;
  ASSERT_EQ(mdb_env_create(&raw), MDB_SUCCESS);
  mdb_env_set_maxdbs(raw, 4);
  ASSERT_EQ(mdb_env_open(raw, dir.path().c_str(), 0, 0640), MDB_SUCCESS);
  MDB_txn* txn;
  MDB_dbi dbi;
  ASSERT_EQ(mdb_txn_begin(raw, nullptr, 0, &txn), MDB_SUCCESS);
  ASSERT_EQ(mdb_dbi_open(txn, "cells", MDB_CREATE, &dbi), MDB_SUCCESS);
  std::vector<uint8_t> key = Key(1), value = Key(2);
  MDB_val k = AsVal(key), v = AsVal(value);
  ASSERT_EQ(mdb_put(txn, dbi, &k, &v, 0), MDB_SUCCESS);
  ASSERT_EQ(mdb_txn_commit(txn), MDB_SUCCESS);
  mdb_env_close(raw);
  auto env = LmdbEnv::Open(dir.path(), Cells());
  ASSERT_EQ(env.status().code(), absl::StatusCode::kFailedPrecondition) << env.status();
  EXPECT_NE(env.status().message().find("without checksums"), std::string::npos) << env.status();
  EXPECT_NE(env.status().message().find(dir.path() + "/data.mdb"), std::string::npos) << env.status();
}

}  // namespace
}  // namespace fremen::storage
