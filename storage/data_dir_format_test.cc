#include "storage/data_dir_format.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "storage/map_info.h"
#include "storage/store.h"
#include "storage/testing/file_damage.h"
#include "storage/testing/labelled_states.h"
#include "storage/verify.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using fremen::testing::TempDir;
using testing::Generic;

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

bool Contains(const absl::Status& status, const std::string& text) {
  return status.message().find(text) != absl::string_view::npos;
}

// A data directory holding maps "alpha" and "beta", closed; returns their catalog records.
std::vector<MapInfo> TwoMaps(const TempDir& dir) {
  auto store = Store::Open(dir.path(), {});
  EXPECT_TRUE(store.ok()) << store.status();
  std::vector<MapInfo> maps;
  for (const char* name : {"alpha", "beta"}) {
    auto created = (*store)->CreateMap(Generic(name));
    EXPECT_TRUE(created.ok()) << created.status();
    maps.push_back(*created);
  }
  return maps;
}

TEST(DataDirFormatTest, ANewDirectoryIsMarkedWithTheFormat) {
  TempDir dir;
  ASSERT_TRUE(Store::Open(dir.path(), {}).ok());
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/FORMAT"), "fremen data directory format 3\n");
  auto format = ReadDataDirFormat(Env::Default(), dir.path());
  ASSERT_TRUE(format.ok()) << format.status();
  EXPECT_EQ(*format, kDataDirFormat);
}

TEST(DataDirFormatTest, AnUnmarkedDirectoryOfThisFormatIsMarkedAndServes) {
  TempDir dir;
  TwoMaps(dir);
  std::filesystem::remove(dir.path() + "/FORMAT");  // as this format wrote it before it kept the file
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  EXPECT_TRUE((*store)->Map("alpha").ok());
  EXPECT_TRUE((*store)->FailedMaps().empty());
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/FORMAT"), "fremen data directory format 3\n");
}

TEST(DataDirFormatTest, AFormat2DirectoryIsMarkedFormat3AndServes) {
  TempDir dir;
  TwoMaps(dir);
  WriteText(dir.path() + "/FORMAT", "fremen data directory format 2\n");
  EXPECT_TRUE(VerifyDataDir(dir.path(), {}).problems.empty());
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  EXPECT_TRUE((*store)->Map("alpha").ok());
  EXPECT_TRUE((*store)->FailedMaps().empty());
  // Marked before any map was opened: a format 2 fremend, which would not read the published
  // models' database, refuses it from now on.
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/FORMAT"), "fremen data directory format 3\n");
}

TEST(DataDirFormatTest, ANewerFormatIsRefusedAndNothingIsOpened) {
  TempDir dir;
  TwoMaps(dir);
  WriteText(dir.path() + "/FORMAT", "fremen data directory format 4\n");
  const std::string catalog_before = testing::ReadWholeFile(dir.path() + "/catalog/data.mdb");
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(absl::IsFailedPrecondition(store.status())) << store.status();
  EXPECT_TRUE(Contains(store.status(), "is data directory format 4, written by a newer fremend; this one reads formats 2 to 3"))
      << store.status();
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/catalog/data.mdb"), catalog_before);
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/FORMAT"), "fremen data directory format 4\n");
  // The offline check says the same and reads no further.
  const DataDirVerifyReport report = VerifyDataDir(dir.path(), {});
  ASSERT_EQ(report.problems.size(), 1u);
  EXPECT_EQ(report.problems[0].file, "FORMAT");
  EXPECT_NE(report.problems[0].what.find("format 4"), std::string::npos) << report.problems[0].what;
  EXPECT_TRUE(report.maps.empty());
}

TEST(DataDirFormatTest, AFormatFileThatSaysSomethingElseIsDataLossNamingIt) {
  TempDir dir;
  ASSERT_TRUE(Store::Open(dir.path(), {}).ok());
  WriteText(dir.path() + "/FORMAT", "fremen data directory format two\n");
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(absl::IsDataLoss(store.status())) << store.status();
  EXPECT_TRUE(Contains(store.status(), dir.path() + "/FORMAT does not say")) << store.status();
}

TEST(DataDirFormatTest, AnUnmarkedDirectoryWithDamagedCatalogRecordsServesWithThoseMapsFailed) {
  // Damage is not a format: the catalog opens, so its damaged records are failed maps as ever.
  TempDir dir;
  const std::vector<MapInfo> maps = TwoMaps(dir);
  std::filesystem::remove(dir.path() + "/FORMAT");
  const std::string catalog = dir.path() + "/catalog/data.mdb";
  for (const MapInfo& info : maps) {
    const std::string encoded = EncodeMapInfo(info);
    const auto copies = testing::FindAll(testing::ReadWholeFile(catalog), testing::Bytes(encoded));
    ASSERT_FALSE(copies.empty()) << info.name;
    for (const size_t at : copies) testing::FlipBit(catalog, at + encoded.size() - 1, 0);
  }
  auto store = Store::Open(dir.path(), {});
  ASSERT_TRUE(store.ok()) << store.status();
  EXPECT_EQ((*store)->FailedMaps().size(), 2u);
  EXPECT_EQ(testing::ReadWholeFile(dir.path() + "/FORMAT"), "fremen data directory format 3\n");
}

}  // namespace
}  // namespace fremen::storage
