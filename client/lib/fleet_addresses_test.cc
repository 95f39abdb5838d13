#include "client/lib/fleet_addresses.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::client {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(FleetAddressesTest, SplitsACommaSeparatedList) {
  EXPECT_THAT(SplitAddressList(" a:1, b:2 ,,c:3 "), ElementsAre("a:1", "b:2", "c:3"));
  EXPECT_TRUE(SplitAddressList("").empty());
}

TEST(FleetAddressesTest, AFleetIsSeveralAddressesOrAnAllName) {
  EXPECT_FALSE(NamesAFleet({"a:1"}));
  EXPECT_TRUE(NamesAFleet({"a:1", "b:1"}));
  EXPECT_TRUE(NamesAFleet({"all:fremend:50051"}));
  EXPECT_FALSE(NamesAFleet({}));
}

TEST(FleetAddressesTest, ResolvesEveryAddressOfAName) {
  auto loopback = ResolveEvery("127.0.0.1:50051");
  ASSERT_TRUE(loopback.ok()) << loopback.status();
  EXPECT_THAT(*loopback, ElementsAre("127.0.0.1:50051"));
  auto v6 = ResolveEvery("::1:7");  // the last ':' splits the port off
  ASSERT_TRUE(v6.ok()) << v6.status();
  EXPECT_THAT(*v6, ElementsAre("[::1]:7"));
  EXPECT_EQ(ResolveEvery("no-port").status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ResolveEvery("no-such-host.invalid:1").status().code(), absl::StatusCode::kUnavailable);
}

TEST(FleetAddressesTest, ExpandsAllNamesInPlaceAndRefusesRepeats) {
  auto expanded = ExpandAddresses({"b:2", "all:127.0.0.1:9", "a:1"});
  ASSERT_TRUE(expanded.ok()) << expanded.status();
  EXPECT_THAT(*expanded, ElementsAre("b:2", "127.0.0.1:9", "a:1"));
  auto twice = ExpandAddresses({"127.0.0.1:9", "all:127.0.0.1:9"});
  EXPECT_EQ(twice.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(twice.status().message(), HasSubstr("127.0.0.1:9 is named twice"));
  EXPECT_EQ(ExpandAddresses({}).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace fremen::client
