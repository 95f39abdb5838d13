#include "server/services/state_page.h"

#include <string>
#include <vector>

#include "gtest/gtest.h"

namespace fremen::server {
namespace {

using storage::StateLabel;

std::vector<StateLabel> Labels(int n) {
  std::vector<StateLabel> labels;
  for (int i = 0; i < n; ++i) labels.push_back(StateLabel{static_cast<uint64_t>(1000 - i), "s" + std::to_string(100 + i), "g"});
  return labels;
}

TEST(StatePageTest, PagesWalkEveryStateOnceInOrder) {
  const std::vector<StateLabel> all = Labels(7);
  std::vector<StateLabel> seen;
  std::string token;
  int pages = 0;
  do {
    auto page = PageOfStates(all, 3, token);
    ASSERT_TRUE(page.ok()) << page.status();
    seen.insert(seen.end(), page->states.begin(), page->states.end());
    token = page->next_page_token;
    ++pages;
  } while (!token.empty());
  EXPECT_EQ(pages, 3);
  EXPECT_EQ(seen, all);
}

TEST(StatePageTest, ATokenStillContinuesAfterItsNameWhenStatesWereAdded) {
  std::vector<StateLabel> all = Labels(4);
  auto first = PageOfStates(all, 2, "");
  ASSERT_TRUE(first.ok());
  // A state sorting before the page's end arrives between the two calls: it is not listed again
  // later, and nothing after the token is skipped.
  all.insert(all.begin(), StateLabel{1, "a-new-one", ""});
  auto second = PageOfStates(all, 2, first->next_page_token);
  ASSERT_TRUE(second.ok());
  ASSERT_EQ(second->states.size(), 2u);
  EXPECT_EQ(second->states[0].name, "s102");
  EXPECT_EQ(second->states[1].name, "s103");
  EXPECT_TRUE(second->next_page_token.empty());
}

TEST(StatePageTest, SizesDefaultAndCapAndBadFieldsAreNamed) {
  const std::vector<StateLabel> all = Labels(1500);
  EXPECT_EQ(PageOfStates(all, 0, "")->states.size(), 100u);
  EXPECT_EQ(PageOfStates(all, 5000, "")->states.size(), 1000u);
  auto negative = PageOfStates(all, -1, "");
  EXPECT_TRUE(absl::IsInvalidArgument(negative.status()));
  EXPECT_NE(negative.status().message().find("page_size"), std::string::npos);
  auto bad = PageOfStates(all, 10, "not a token!");
  EXPECT_TRUE(absl::IsInvalidArgument(bad.status()));
  EXPECT_NE(bad.status().message().find("page_token"), std::string::npos);
  EXPECT_TRUE(PageOfStates({}, 10, "")->states.empty());
}

}  // namespace
}  // namespace fremen::server
