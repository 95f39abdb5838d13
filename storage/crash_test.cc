// Crash safety (docs/storage.md, "Recovery": after kill -9 at any moment, a restart recovers every
// acknowledged batch and the models equal a from-scratch computation over exactly those batches): a
// child process ingests scans and is SIGKILLed at random moments, mid-write, mid-sync or
// mid-checkpoint; after each kill the store is reopened here and compared with a reference fed
// exactly the batches it holds.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <thread>

#include "storage/map_store.h"
#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

constexpr uint64_t kScans = 4000;
constexpr size_t kCells = 300;

// Runs the child for about `millis` ms, then SIGKILLs it; returns the last acknowledged sequence.
uint64_t RunAndKill(const std::string& dir, int millis) {
  int out[2];
  EXPECT_EQ(pipe(out), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    close(out[1]);
    const std::string scans = std::to_string(kScans), cells = std::to_string(kCells);
    execl(FREMEN_CRASH_CHILD, FREMEN_CRASH_CHILD, dir.c_str(), scans.c_str(), cells.c_str(), nullptr);
    _exit(127);
  }
  close(out[1]);
  std::this_thread::sleep_for(std::chrono::milliseconds(millis));
  kill(pid, SIGKILL);
  int status;
  waitpid(pid, &status, 0);
  std::string text;
  char buffer[4096];
  ssize_t n;
  while ((n = read(out[0], buffer, sizeof buffer)) > 0) text.append(buffer, n);
  close(out[0]);
  uint64_t last = 0;
  for (size_t pos = text.rfind("ack "); pos != std::string::npos;) {
    const size_t end = text.find('\n', pos);
    if (end != std::string::npos) last = std::stoull(text.substr(pos + 4, end - pos - 4));
    break;
  }
  return last;
}

TEST(CrashTest, EveryAcknowledgedBatchSurvivesKillNineAndModelsMatchARecomputation) {
  fremen::testing::TempDir dir, reference_dir;
  const MapInfo map = testing::GridMap("crash", 48, 48, 4, 2);
  auto reference = MapStore::Open(map, reference_dir.path(), {});
  ASSERT_TRUE(reference.ok());
  uint64_t applied_to_reference = 0;
  std::mt19937 rng(20261121);
  uint64_t previous_acked = 0;
  for (int round = 0; round < 24; ++round) {
    const uint64_t acked = RunAndKill(dir.path(), std::uniform_int_distribution<int>(40, 400)(rng));
    previous_acked = std::max(previous_acked, acked);
    auto store = MapStore::Open(map, dir.path(), {});
    ASSERT_TRUE(store.ok()) << "round " << round << ": " << store.status();
    // Every scan has kCells valid observations, so the count says how many batches the store holds.
    const uint64_t observations = (*store)->Stats().totals.observations;
    ASSERT_EQ(observations % kCells, 0u);
    const uint64_t held = observations / kCells;
    ASSERT_GE(held, previous_acked) << "round " << round << ": an acknowledged batch was lost";
    ASSERT_LE(held, previous_acked + 1) << "round " << round;  // at most the one in flight
    for (; applied_to_reference < held; ++applied_to_reference) {
      ASSERT_TRUE((*reference)->Write(testing::SweepScan(map, 1, applied_to_reference, kCells)).ok());
    }
    size_t compared = 0;
    for (uint32_t x = 0; x < 48; x += 3) {
      for (uint32_t y = 0; y < 48; ++y) {
        for (uint32_t z = 0; z < 4; ++z) {
          const uint64_t key = map.grid.keys().Key(x, y, z);
          const auto got = (*store)->Snapshot(key), want = (*reference)->Snapshot(key);
          ASSERT_EQ(got.has_value(), want.has_value());
          if (!got) continue;
          ++compared;
          ASSERT_EQ(got->is_static, want->is_static) << key;
          if (got->is_static) {
            ASSERT_EQ(got->static_state, want->static_state) << key;
          } else {
            ASSERT_EQ(got->model->spectrum(), want->model->spectrum()) << key;
            ASSERT_EQ(got->model->persistence(), want->model->persistence()) << key;
            ASSERT_EQ(got->model->order_errors(), want->model->order_errors()) << key;
          }
        }
      }
    }
    if (held > 0) {
      EXPECT_GT(compared, 0u);
    }
    std::fprintf(stderr, "round %d: acked %llu held %llu\n", round, (unsigned long long)acked, (unsigned long long)held);
    previous_acked = held;  // the next run continues after the store's last sequence
  }
  EXPECT_GT(applied_to_reference, 100u);  // the rounds did real work
}

}  // namespace
}  // namespace fremen::storage
