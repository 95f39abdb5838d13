#include "client/lib/placement.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"

namespace fremen::client {
namespace {

using ::testing::HasSubstr;

std::vector<std::string> MapNames(int count) {
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) names.push_back(absl::StrCat("building-", i));
  return names;
}

Placement Fleet(std::vector<std::string> daemons) {
  auto placement = Placement::Create(std::move(daemons));
  EXPECT_TRUE(placement.ok()) << placement.status();
  return *std::move(placement);
}

const std::vector<std::string> kThree = {"fremend-0.fremend:50051", "fremend-1.fremend:50051",
                                         "fremend-2.fremend:50051"};

TEST(PlacementTest, Crc32IsTheIeeeChecksumNginxUses) {
  // The check value of CRC-32/ISO-HDLC, the checksum of ngx_crc32_long and zlib.
  EXPECT_EQ(Placement::Crc32("123456789"), 0xCBF43926u);
  EXPECT_EQ(Placement::Crc32(""), 0u);
}

TEST(PlacementTest, OwnersAreDeterministicAndIndependentOfTheDaemonsOrder) {
  const Placement a = Fleet(kThree);
  const Placement b = Fleet({kThree[2], kThree[0], kThree[1]});
  for (const std::string& map : MapNames(500)) {
    EXPECT_EQ(a.Owner(map), b.Owner(map)) << map;
    EXPECT_EQ(a.Owner(map), Fleet(kThree).Owner(map)) << map;
  }
}

// Pinned answers of nginx 1.22.1 for `hash $http_x_fremen_map consistent` over these three
// servers (observed through a real nginx; tests/fleet_routing_test.cc checks the same for every
// map it creates), so that a change of the ring shows here without nginx.
TEST(PlacementTest, MatchesOwnersObservedThroughNginx) {
  const Placement fleet = Fleet({"127.0.0.1:50051", "127.0.0.1:50061", "127.0.0.1:50071"});
  const std::map<std::string, std::string> observed = {
      {"m1", "127.0.0.1:50071"},          {"m2", "127.0.0.1:50071"},     {"m3", "127.0.0.1:50061"},
      {"m4", "127.0.0.1:50061"},          {"m5", "127.0.0.1:50071"},     {"m6", "127.0.0.1:50051"},
      {"m7", "127.0.0.1:50061"},          {"m8", "127.0.0.1:50071"},     {"m9", "127.0.0.1:50061"},
      {"m10", "127.0.0.1:50061"},         {"m11", "127.0.0.1:50071"},    {"m12", "127.0.0.1:50061"},
      {"office", "127.0.0.1:50051"},      {"lab", "127.0.0.1:50051"},    {"warehouse-7", "127.0.0.1:50051"},
      {"hospital.wing-b", "127.0.0.1:50071"}, {"a", "127.0.0.1:50071"},
  };
  for (const auto& [map, owner] : observed) EXPECT_EQ(fleet.Owner(map), owner) << map;
}

TEST(PlacementTest, SpreadsMapsRoughlyEvenly) {
  const Placement fleet = Fleet(kThree);
  std::map<std::string, int> held;
  const std::vector<std::string> maps = MapNames(3000);
  for (const std::string& map : maps) ++held[fleet.Owner(map)];
  ASSERT_EQ(held.size(), 3u);
  // 160 points per daemon: shares within about ±10% of a third; a broken ring gives far worse.
  for (const auto& [daemon, count] : held) {
    EXPECT_GT(count, 3000 * 0.22) << daemon;
    EXPECT_LT(count, 3000 * 0.45) << daemon;
  }
}

TEST(PlacementTest, AddingADaemonMovesOnlyMapsToTheNewDaemon) {
  const Placement three = Fleet(kThree);
  std::vector<std::string> four_daemons = kThree;
  four_daemons.push_back("fremend-3.fremend:50051");
  const Placement four = Fleet(four_daemons);
  int moved = 0;
  const std::vector<std::string> maps = MapNames(3000);
  for (const std::string& map : maps) {
    if (three.Owner(map) == four.Owner(map)) continue;
    EXPECT_EQ(four.Owner(map), "fremend-3.fremend:50051") << map << " moved between old daemons";
    ++moved;
  }
  // About a quarter move (a modulo hash would move three quarters).
  EXPECT_GT(moved, 3000 * 0.12);
  EXPECT_LT(moved, 3000 * 0.38);
}

TEST(PlacementTest, RemovingADaemonMovesOnlyItsMaps) {
  const Placement three = Fleet(kThree);
  const Placement two = Fleet({kThree[0], kThree[2]});
  for (const std::string& map : MapNames(1000)) {
    if (three.Owner(map) != kThree[1]) EXPECT_EQ(two.Owner(map), three.Owner(map)) << map;
  }
}

TEST(PlacementTest, OneDaemonHoldsEverything) {
  const Placement one = Fleet({"solo:50051"});
  for (const std::string& map : MapNames(50)) EXPECT_EQ(one.Owner(map), "solo:50051");
}

TEST(PlacementTest, ThePortIsPartOfTheName) {
  // nginx hashes HOST "\0" PORT: the same hosts on other ports make another ring, which is why
  // the HTTP port is routed by the gRPC ring's choice (deploy/nginx/fremen.conf).
  const Placement grpc = Fleet({"a:50051", "b:50051", "c:50051"});
  const Placement http = Fleet({"a:50052", "b:50052", "c:50052"});
  int differ = 0;
  for (const std::string& map : MapNames(300)) {
    const std::string host = grpc.Owner(map).substr(0, 1);
    if (http.Owner(map).substr(0, 1) != host) ++differ;
  }
  EXPECT_GT(differ, 0);
}

TEST(PlacementTest, ParseSplitsACommaSeparatedList) {
  auto fleet = Placement::Parse("a:1, b:2 ,c:3");
  ASSERT_TRUE(fleet.ok()) << fleet.status();
  EXPECT_THAT(fleet->daemons(), ::testing::ElementsAre("a:1", "b:2", "c:3"));
}

TEST(PlacementTest, RefusesEmptyAndRepeatedDaemons) {
  EXPECT_THAT(Placement::Create({}).status().message(), HasSubstr("at least one daemon"));
  EXPECT_THAT(Placement::Parse("a:1,,b:2").status().message(), HasSubstr("empty"));
  EXPECT_THAT(Placement::Parse("a:1,b:2,a:1").status().message(), HasSubstr("\"a:1\" is listed twice"));
  EXPECT_EQ(Placement::Create({}).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace fremen::client
