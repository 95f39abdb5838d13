// UninitializedVector<T>: a std::vector whose resize leaves new elements of a trivial T
// uninitialized, for a buffer that is written whole right after it is sized. std::vector value-
// initializes them (a memset): on the ingest path that zero-fill of a batch's keys and values, 12
// bytes a cell overwritten at once by the compact scan's expansion, cost the daemon about 8 % of
// its CPU time on the office load (docs/performance.md, "The zero fill of the decoded arrays").
//
// Everything else is std::vector's: push_back, assign(n, v), insert and copies construct as usual.
// It compares equal to a std::vector<T> of the same elements (found by argument-dependent lookup
// through the allocator's namespace), so tests can write the expected keys as a std::vector.
#pragma once

#include <algorithm>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace fremen {

// std::allocator, except that construct() with no arguments default-initializes.
template <typename T>
class DefaultInitAllocator : public std::allocator<T> {
 public:
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}  // NOLINT: converting, as std::allocator's

  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <typename T>
using UninitializedVector = std::vector<T, DefaultInitAllocator<T>>;

template <typename T>
bool operator==(const UninitializedVector<T>& a, const std::vector<T>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end());
}
template <typename T>
bool operator==(const std::vector<T>& a, const UninitializedVector<T>& b) {
  return b == a;
}

}  // namespace fremen
