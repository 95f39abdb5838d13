// Test support: a MapStore opened for a test, or nullptr with the failure recorded (EXPECT), so
// that a test ASSERTs on the pointer and the reason shows in its output.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "storage/map_store.h"

namespace fremen::storage::testing {

// The map `info` opened on `dir` with `options`; nullptr, with a test failure naming why, when it
// does not open.
inline std::unique_ptr<MapStore> OpenOrDie(const MapInfo& info, const std::string& dir, StoreOptions options = {}) {
  auto store = MapStore::Open(info, dir, options);
  EXPECT_TRUE(store.ok()) << store.status();
  return store.ok() ? *std::move(store) : nullptr;
}

}  // namespace fremen::storage::testing
