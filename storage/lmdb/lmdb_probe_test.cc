#include "storage/lmdb/lmdb_probe.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "storage/lmdb/lmdb_env.h"
#include "storage/testing/file_damage.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

LmdbOptions Cells() {
  LmdbOptions options;
  options.databases = {"cells", "more"};
  return options;
}

// An environment with enough records for a tree of many leaf pages (20000 records of 100 bytes: about
// 600 pages of 4 KiB).
void WriteManyRecords(const std::string& dir) {
  auto env = LmdbEnv::Open(dir, Cells());
  ASSERT_TRUE(env.ok()) << env.status();
  ASSERT_TRUE((*env)
                  ->Write([](LmdbTxn& txn) -> absl::Status {
                    for (uint64_t i = 0; i < 20000; ++i) {
                      uint8_t key[8];
                      for (int b = 0; b < 8; ++b) key[b] = static_cast<uint8_t>(i >> (56 - 8 * b));
                      const std::vector<uint8_t> value(100, static_cast<uint8_t>('a' + i % 26));
                      if (absl::Status s = txn.Put(*txn.Db(i % 2 == 0 ? "cells" : "more"), key, value); !s.ok())
                        return s;
                    }
                    return absl::OkStatus();
                  })
                  .ok());
}

// What a load does: every record of every database.
absl::Status ReadEverything(const std::string& dir) {
  auto env = LmdbEnv::Open(dir, Cells());
  if (!env.ok()) return env.status();
  return (*env)->Read([](LmdbTxn& txn) -> absl::Status {
    for (const char* db : {"cells", "more"}) {
      if (absl::Status s = txn.Scan(*txn.Db(db), {}, {}, [](auto, auto) { return true; }); !s.ok()) return s;
    }
    return absl::OkStatus();
  });
}

TEST(LmdbProbeTest, HealthyEnvironmentsPassAndMissingOnesAreSkipped) {
  fremen::testing::TempDir dir;
  WriteManyRecords(dir.path() + "/a");
  WriteManyRecords(dir.path() + "/b");
  EXPECT_TRUE(ProbeEnvironments({dir.path() + "/a", dir.path() + "/b", dir.path() + "/never-created"}).ok());
  EXPECT_TRUE(ProbeEnvironments({}).ok());
  // The probe changed nothing: the environment opens and reads as before.
  EXPECT_TRUE(ReadEverything(dir.path() + "/a").ok());
}

// The case the probe exists for: a zeroed page in the middle of a data file makes LMDB abort the process that reads it.
// The probe's child takes the abort; the caller gets DataLoss naming the file.
TEST(LmdbProbeTest, AZeroedPageIsReportedNamingTheFileInsteadOfAborting) {
  fremen::testing::TempDir dir;
  const std::string good = dir.path() + "/good", bad = dir.path() + "/bad";
  WriteManyRecords(good);
  WriteManyRecords(bad);
  testing::ZeroPage(bad + "/data.mdb", 100);
  // Without the probe, reading the file kills the process (here a death test's child).
  EXPECT_DEATH((void)ReadEverything(bad), "Assertion");
  const absl::Status probed = ProbeEnvironments({good, bad});
  ASSERT_TRUE(absl::IsDataLoss(probed)) << probed;
  EXPECT_NE(probed.message().find(bad + "/data.mdb is damaged: LMDB aborted reading it (signal 6"), std::string::npos)
      << probed;
  EXPECT_NE(probed.message().find("Assertion"), std::string::npos) << probed;  // LMDB's own words
  EXPECT_TRUE(ProbeEnvironments({good}).ok());
}

TEST(LmdbProbeTest, AnUnreadableFileIsDataLossNotAnAbort) {
  fremen::testing::TempDir dir;
  const std::string env_dir = dir.path() + "/garbage";
  std::filesystem::create_directories(env_dir);
  testing::WriteWholeFile(env_dir + "/data.mdb", std::string(3 * 4096, 'x'));
  const absl::Status probed = ProbeEnvironments({env_dir});
  EXPECT_TRUE(absl::IsDataLoss(probed)) << probed;
  EXPECT_NE(probed.message().find(env_dir + "/data.mdb is damaged"), std::string::npos) << probed;
}

TEST(LmdbProbeTest, AWalkThatDoesNotEndIsStoppedAtTheTimeout) {
  // A zero timeout stands for a walk that never ends: the child is killed, the file reported.
  fremen::testing::TempDir dir;
  WriteManyRecords(dir.path() + "/a");
  const absl::Status probed = ProbeEnvironments({dir.path() + "/a"}, {.timeout = absl::ZeroDuration()});
  EXPECT_TRUE(absl::IsDataLoss(probed)) << probed;
  EXPECT_NE(probed.message().find("did not finish reading it within"), std::string::npos) << probed;
}

}  // namespace
}  // namespace fremen::storage
