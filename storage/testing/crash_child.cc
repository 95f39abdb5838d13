// The ingesting process of the crash test (storage/crash_test.cc): opens a map store, writes scans
// 1..N of a fixed sweep — from the first one the store does not have (MapStore::LastSequence, as a
// writer that lost its count does) — and prints "ack <seq>" for every acknowledged batch, flushed,
// so that the parent knows what was acknowledged before it SIGKILLs this process at a random
// moment.
//
// Usage: fremen_crash_child DIR SCANS CELLS
#include <cstdio>
#include <cstdlib>

#include "storage/map_store.h"
#include "storage/testing/scans.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s DIR SCANS CELLS\n", argv[0]);
    return 2;
  }
  using namespace fremen::storage;
  const MapInfo map = testing::GridMap("crash", 48, 48, 4, 2);
  StoreOptions options;
  options.checkpoint_log_bytes = 200 << 10;  // checkpoints often: a kill may land in one
  options.log_segment_bytes = 64 << 10;
  auto store = MapStore::Open(map, argv[1], options);
  if (!store.ok()) {
    std::fprintf(stderr, "open: %s\n", std::string(store.status().message()).c_str());
    return 1;
  }
  const uint64_t scans = std::strtoull(argv[2], nullptr, 10);
  const size_t cells = std::strtoull(argv[3], nullptr, 10);
  for (uint64_t i = (*store)->LastSequence(1); i < scans; ++i) {
    auto ack = (*store)->Write(testing::SweepScan(map, 1, i, cells));
    if (!ack.ok()) {
      std::fprintf(stderr, "write: %s\n", std::string(ack.status().message()).c_str());
      return 1;
    }
    std::printf("ack %llu\n", static_cast<unsigned long long>(i + 1));
    std::fflush(stdout);
  }
  return 0;
}
