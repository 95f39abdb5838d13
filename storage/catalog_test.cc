#include "storage/catalog.h"

#include <gtest/gtest.h>

#include <set>

#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

MapInfo Named(const std::string& name) {
  MapInfo info;
  info.name = name;
  info.grid.size = {64, 64, 1};
  return info;
}

TEST(CatalogTest, CreateGetDeleteWithUniqueNamesAndIds) {
  fremen::testing::TempDir dir;
  auto catalog = Catalog::Open(dir.path());
  ASSERT_TRUE(catalog.ok()) << catalog.status();
  auto a = (*catalog)->Create(Named("a"), 2);
  auto b = (*catalog)->Create(Named("b"), 2);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NE(a->id, b->id);
  EXPECT_EQ(a->shards, 2u);
  EXPECT_GT(a->created_unix, 0);
  EXPECT_TRUE(absl::IsAlreadyExists((*catalog)->Create(Named("a"), 2).status()));
  auto got = (*catalog)->Get("a");
  ASSERT_TRUE(got.ok());
  EXPECT_EQ(*got, *a);
  EXPECT_TRUE(absl::IsNotFound((*catalog)->Get("zzz").status()));
  ASSERT_TRUE((*catalog)->Delete("a").ok());
  EXPECT_TRUE(absl::IsNotFound((*catalog)->Get("a").status()));
  EXPECT_TRUE(absl::IsNotFound((*catalog)->Delete("a")));
  // Ids are never reused, even after a delete and a reopen.
  catalog->reset();
  catalog = Catalog::Open(dir.path());
  ASSERT_TRUE(catalog.ok());
  auto c = (*catalog)->Create(Named("a"), 1);
  ASSERT_TRUE(c.ok());
  EXPECT_GT(c->id, b->id);
}

TEST(CatalogTest, InvalidMapsAreRefusedNamingTheField) {
  fremen::testing::TempDir dir;
  auto catalog = Catalog::Open(dir.path());
  ASSERT_TRUE(catalog.ok());
  MapInfo bad = Named("x");
  bad.grid.resolution = 0;
  const auto created = (*catalog)->Create(bad, 1);
  ASSERT_TRUE(absl::IsInvalidArgument(created.status()));
  EXPECT_NE(created.status().message().find("grid.resolution"), std::string::npos);
}

TEST(CatalogTest, ListPagesThroughEveryMapOnce) {
  fremen::testing::TempDir dir;
  auto catalog = Catalog::Open(dir.path());
  ASSERT_TRUE(catalog.ok());
  for (int i = 0; i < 25; ++i) ASSERT_TRUE((*catalog)->Create(Named("map" + std::to_string(100 + i)), 1).ok());
  std::set<std::string> seen;
  std::string token;
  int pages = 0;
  do {
    auto page = (*catalog)->List(10, token);
    ASSERT_TRUE(page.ok()) << page.status();
    for (const MapInfo& m : page->maps) EXPECT_TRUE(seen.insert(m.name).second) << m.name;
    token = page->next_page_token;
    ++pages;
  } while (!token.empty());
  EXPECT_EQ(seen.size(), 25u);
  EXPECT_EQ(pages, 3);
  EXPECT_TRUE(absl::IsInvalidArgument((*catalog)->List(5000, "").status()));
  EXPECT_TRUE(absl::IsInvalidArgument((*catalog)->List(10, "garbage").status()));
  auto empty = Catalog::Open(dir.path() + "-other");
  ASSERT_TRUE(empty.ok());
  auto nothing = (*empty)->List(0, "");
  ASSERT_TRUE(nothing.ok());
  EXPECT_TRUE(nothing->maps.empty());
  std::filesystem::remove_all(dir.path() + "-other");
}

}  // namespace
}  // namespace fremen::storage
