#include "server/rpc/map_name.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

TEST(ResolveMapNameTest, FieldOrHeaderOrBothAgreeing) {
  EXPECT_EQ(*ResolveMapName(std::nullopt, "lab", "map"), "lab");
  EXPECT_EQ(*ResolveMapName("lab", "", "map"), "lab");
  EXPECT_EQ(*ResolveMapName("lab", "lab", "map"), "lab");
  EXPECT_EQ(*ResolveMapName("", "lab", "map"), "lab");  // an empty header is no header
}

TEST(ResolveMapNameTest, DisagreementIsInvalidArgumentNamingTheField) {
  const absl::Status status = ResolveMapName("lab", "office", "map.name").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("map.name is \"office\" but the x-fremen-map header says \"lab\""));
}

TEST(ResolveMapNameTest, NeitherIsInvalidArgument) {
  const absl::Status status = ResolveMapName(std::nullopt, "", "map").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("map is required"));
}

}  // namespace
}  // namespace fremen::server
