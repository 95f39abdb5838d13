#include "base/uninitialized_vector.h"

#include <string>

#include "gtest/gtest.h"

namespace fremen {
namespace {

TEST(UninitializedVectorTest, ResizeKeepsTheElementsThereAndConstructsWithArgumentsAsUsual) {
  UninitializedVector<uint64_t> v = {7, 8, 9};
  v.resize(1000);
  v.resize(2);
  EXPECT_EQ(v, (std::vector<uint64_t>{7, 8}));
  v.assign(3, 5);
  EXPECT_EQ(v, (std::vector<uint64_t>{5, 5, 5}));
  v.push_back(6);
  v.insert(v.begin(), 4);
  EXPECT_EQ(v, (std::vector<uint64_t>{4, 5, 5, 5, 6}));
  EXPECT_NE(v, (std::vector<uint64_t>{4, 5, 5, 5}));
  EXPECT_NE((std::vector<uint64_t>{4, 5, 5, 5, 7}), v);
}

TEST(UninitializedVectorTest, AClassStillHasItsConstructorRun) {
  // Default-initialization runs a class's default constructor: only trivial types are left as they lie.
  UninitializedVector<std::string> v;
  v.resize(3);
  EXPECT_EQ(v, (std::vector<std::string>{"", "", ""}));
}

TEST(UninitializedVectorTest, CopiesAndMovesKeepTheElements) {
  UninitializedVector<float> a(4);
  for (size_t i = 0; i < a.size(); ++i) a[i] = static_cast<float>(i) / 2;
  const UninitializedVector<float> b = a;
  const UninitializedVector<float> c = std::move(a);
  EXPECT_EQ(b, c);
  EXPECT_EQ(b, (std::vector<float>{0, 0.5f, 1, 1.5f}));
}

}  // namespace
}  // namespace fremen
