// Load generator for the update job (README.md, "Benchmarks"): prints figures, asserts nothing.
//
//  1. choose + publish, states/s per core (K = 24, L = 5): a 1M-dynamic-state grid map with one
//     shard, PublishModels timed (the store's path: order choice, top-L, flags, under the shard's
//     lock in chunks).
//  2. a 1M-dynamic-state map updated on 2 cores (2 shards) including persistence: PublishModels then
//     the checkpoint that writes every republished state to LMDB; and a second run with nothing new.
//  3. ingest rate while a publication runs vs without: 10k-cell coherent scans, 8 in flight; and
//     while the checkpoint after it writes the 1M republished states.
//  4. lossless: the update of one state with 30 days of 5-s history plus a new day (17,280 slots),
//     measured on --lossless-states copies and extrapolated to 10k cells on 2 cores: every cell
//     dynamic, and 1 in 20 dynamic with the rest constant (a building: the constant ones skip the FFT);
//     beside them the FFT alone of the dynamic states (SlotSpectrum::Compute), a full-length
//     update's ceiling.
// Medians of --runs runs (default 3). Run it with `nice -n 10` on a shared machine.
//
// Usage: fremen_update_bench [--runs N] [--lossless-states N] [--lossless-mix MIX] [--dir DIR] [--parts DIGITS]
//   --parts: which of the four to run, e.g. 4 for the lossless update alone (default 1234).
//   --lossless-mix: "dynamic" (every cell dynamic), "office" (1 in 20) or "both" (default); one mix
//     alone is what scripts/lossless-instructions.sh counts under callgrind.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "storage/map_store.h"
#include "storage/model/lossless/bin_spectrum.h"
#include "storage/model/lossless/lossless_history.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using Clock = std::chrono::steady_clock;
constexpr uint32_t kSide = 1024;  // 1024 × 1024 = 1,048,576 cells
constexpr double kT0 = 1.7e9;

double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Bytes this process has passed to write calls so far (/proc/self/io's wchar; LMDB writes its
// pages with write calls), 0 where that is not available.
uint64_t BytesWritten() {
  std::FILE* f = std::fopen("/proc/self/io", "r");
  if (f == nullptr) return 0;
  unsigned long long wchar = 0;
  char line[128];
  while (std::fgets(line, sizeof line, f) != nullptr) {
    if (std::sscanf(line, "wchar: %llu", &wchar) == 1) break;
  }
  std::fclose(f);
  return wchar;
}

// Seconds to write `bytes` to a new file at `path` in 1 MiB writes and fdatasync it once.
double SequentialWriteSeconds(const std::string& path, uint64_t bytes) {
  std::vector<char> block(1 << 20, 'x');
  const auto start = Clock::now();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return 0;
  for (uint64_t written = 0; written < bytes;) {
    const ssize_t n = ::write(fd, block.data(), std::min<uint64_t>(block.size(), bytes - written));
    if (n <= 0) break;
    written += static_cast<uint64_t>(n);
  }
  ::fdatasync(fd);
  ::close(fd);
  const double seconds = Seconds(start, Clock::now());
  std::filesystem::remove(path);
  return seconds;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

MapInfo Grid(const std::string& name, uint32_t shards) {
  MapInfo info;
  info.name = name;
  info.grid.size = {kSide, kSide, 1};
  info.shards = shards;
  return info;
}

// Rows [y0, y1) of the grid at time t: a checkerboard, inverted when `flip`, so that every cell seen
// with both is dynamic. Keys sorted, as robots send them.
ObservationBatch Rows(const MapInfo& map, uint64_t writer, uint64_t i, uint32_t y0, uint32_t y1, double t, bool flip) {
  std::vector<std::pair<uint64_t, float>> cells;
  for (uint32_t y = y0; y < y1; ++y) {
    for (uint32_t x = 0; x < kSide; ++x) {
      cells.emplace_back(map.grid.keys().Key(x, y, 0), ((x + y) % 2 == 0) != flip ? 1.0f : 0.0f);
    }
  }
  std::sort(cells.begin(), cells.end());
  ObservationBatch b;
  b.writer_id = writer;
  b.sequence = i + 1;
  b.time = t;
  for (const auto& [key, value] : cells) {
    b.keys.push_back(key);
    b.values.push_back(value);
  }
  return b;
}

// Observes every cell (in 64-row scans), inverting the last values, so that every cell is dynamic
// and the next publication has all of them to do.
void TouchAll(MapStore& store, uint64_t& sequence, double t) {
  static bool flip = false;
  flip = !flip;
  for (uint32_t y = 0; y < kSide; y += 64) {
    if (!store.Write(Rows(store.info(), 1, sequence++, y, y + 64, t, flip)).ok()) std::exit(1);
  }
}

std::unique_ptr<MapStore> OpenMap(const std::string& dir, uint32_t shards) {
  StoreOptions options;
  options.checkpoint_log_bytes = UINT64_MAX;  // checkpoints only when the bench asks
  auto store = MapStore::Open(Grid("bench", shards), dir, options);
  if (!store.ok()) std::fprintf(stderr, "%s\n", std::string(store.status().message()).c_str()), std::exit(1);
  return *std::move(store);
}

// Submits scans of 10 rows (10,240 cells) with 8 in flight until `stop`; returns cell-observations
// per second.
double IngestUntil(MapStore& store, uint64_t& sequence, double t, const std::function<bool()>& stop) {
  std::mutex m;
  std::condition_variable cv;
  int outstanding = 0;
  uint64_t observations = 0;
  const auto start = Clock::now();
  for (uint32_t row = 0; !stop(); row = (row + 10) % (kSide - 10)) {
    ObservationBatch b = Rows(store.info(), 2, sequence++, row, row + 10, t, row % 20 == 0);
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return outstanding < 8; });
    ++outstanding;
    lock.unlock();
    const absl::Status s = store.Submit(std::move(b), [&](absl::StatusOr<BatchAck> ack) {
      std::lock_guard l(m);
      if (ack.ok()) observations += ack->accepted;
      --outstanding;
      cv.notify_all();
    });
    if (!s.ok()) {
      std::lock_guard l(m);
      --outstanding;
    }
  }
  std::unique_lock lock(m);
  cv.wait(lock, [&] { return outstanding == 0; });
  return observations / Seconds(start, Clock::now());
}

// A 30-day history of 5-s slots plus one new day, updated once after the 30 days. A dynamic cell
// has a daily rhythm and noise (1 slot in 50 flipped); a static one (a wall) reads occupied always.
model::LosslessHistory LosslessCell(bool dynamic) {
  constexpr double kDelta = 5;
  constexpr uint64_t kDaySlots = 17280;
  auto history = *model::LosslessHistory::Create(kT0, kDelta);
  uint64_t noise = 88172645463325252ull;
  const auto add = [&](uint64_t i) {
    noise ^= noise << 13, noise ^= noise >> 7, noise ^= noise << 17;
    const bool day = (i % kDaySlots) > kDaySlots / 3 && (i % kDaySlots) < 2 * kDaySlots / 3;
    (void)history.AddSlot(i, dynamic ? day != (noise % 50 == 0) : true);
  };
  for (uint64_t i = 0; i < 30 * kDaySlots; ++i) add(i);
  (void)history.Update(5);
  for (uint64_t i = 30 * kDaySlots; i < 31 * kDaySlots; ++i) add(i);
  return history;
}

// Seconds per state of the night's update of `cells` on 2 threads.
double LosslessNight(const std::vector<model::LosslessHistory>& cells) {
  std::vector<model::LosslessHistory> copies = cells;
  const auto start = Clock::now();
  std::thread other([&] {
    for (size_t i = 1; i < copies.size(); i += 2) (void)copies[i].Update(5);
  });
  for (size_t i = 0; i < copies.size(); i += 2) (void)copies[i].Update(5);
  other.join();
  return Seconds(start, Clock::now()) / static_cast<double>(copies.size());
}

// Seconds per state of the transform alone (SlotSpectrum::Compute of the reconstructed signal) of
// `cells` on 2 threads: the ceiling of a full-length update, measured beside it.
double TransformOnly(const std::vector<model::LosslessHistory>& cells) {
  std::vector<std::vector<model::SlotState>> signals;
  for (const auto& cell : cells) signals.push_back(*cell.Reconstruct(0, cell.slot_count()));
  const auto start = Clock::now();
  std::thread other([&] {
    for (size_t i = 1; i < signals.size(); i += 2) (void)model::SlotSpectrum::Compute(signals[i]);
  });
  for (size_t i = 0; i < signals.size(); i += 2) (void)model::SlotSpectrum::Compute(signals[i]);
  other.join();
  return Seconds(start, Clock::now()) / static_cast<double>(signals.size());
}

}  // namespace
}  // namespace fremen::storage

int main(int argc, char** argv) {
  using namespace fremen::storage;
  int runs = 3;
  int lossless_states = 200;
  std::string base;
  std::string parts = "1234";
  std::string mix = "both";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--runs")) runs = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--lossless-states")) lossless_states = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--dir")) base = argv[i + 1];
    if (!std::strcmp(argv[i], "--parts")) parts = argv[i + 1];
    if (!std::strcmp(argv[i], "--lossless-mix")) mix = argv[i + 1];
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  fremen::testing::TempDir temp;
  if (base.empty()) base = temp.path();
  constexpr double kStates = double{kSide} * kSide;

  const auto wants = [&parts](char part) { return parts.find(part) != std::string::npos; };

  // 1. One shard: states/s of one core.
  double one_core_publish_rate = 0;  // states/s, from (1) when it runs
  if (wants('1')) {
    auto store = OpenMap(base + "/one", 1);
    uint64_t sequence = 0;
    std::vector<double> rates;
    for (int r = 0; r < runs; ++r) {
      TouchAll(*store, sequence, kT0 + 3600.0 * sequence);
      TouchAll(*store, sequence, kT0 + 3600.0 * sequence);
      const auto start = Clock::now();
      const auto published = store->PublishModels();
      if (!published.ok()) return std::fprintf(stderr, "%s\n", std::string(published.status().message()).c_str()), 1;
      rates.push_back(static_cast<double>(*published) / Seconds(start, Clock::now()));
    }
    std::printf("choose + publish, 1 shard (1 core), K=24 L=5: %.2fM states/s (median of %d; target >= 2M/s/core)\n",
                Median(rates) / 1e6, runs);
    one_core_publish_rate = Median(rates);
  }

  // 2. Two shards on two cores, with the checkpoint that persists every republished state.
  auto store = wants('2') || wants('3') ? OpenMap(base + "/two", 2) : nullptr;
  uint64_t sequence = 0;
  if (wants('2')) {
    std::vector<double> publish, persist, again, persisted_bytes;
    for (int r = 0; r < runs; ++r) {
      TouchAll(*store, sequence, kT0 + 3600.0 * sequence);
      TouchAll(*store, sequence, kT0 + 3600.0 * sequence);
      (void)store->Checkpoint();
      const auto start = Clock::now();
      const auto published = store->PublishModels();
      const auto mid = Clock::now();
      const uint64_t written_before = BytesWritten();
      (void)store->Checkpoint();
      const auto end = Clock::now();
      persisted_bytes.push_back(static_cast<double>(BytesWritten() - written_before));
      if (!published.ok() || *published != kStates) {
        std::fprintf(stderr, "the publication did not publish every state: %s\n",
                     published.ok() ? std::to_string(*published).c_str() : std::string(published.status().message()).c_str());
      }
      publish.push_back(Seconds(start, mid));
      persist.push_back(Seconds(mid, end));
      const auto second = Clock::now();
      (void)store->PublishModels();
      again.push_back(Seconds(second, Clock::now()));
    }
    std::printf("1M dynamic states, 2 shards (2 cores): publish %.3f s + persist (checkpoint) %.3f s = %.3f s "
                "(medians of %d; target <= 1 s)\n",
                Median(publish), Median(persist), Median(publish) + Median(persist), runs);
    // Ceilings of the same run: the publication kernel at (1)'s rate on both cores, and the disk
    // writing as many bytes as the checkpoint wrote, sequentially into one file, with one sync.
    if (one_core_publish_rate > 0) {
      std::printf("  ceilings of this run: publishing 1M states on 2 cores at (1)'s rate %.3f s;",
                  kStates / (2 * one_core_publish_rate));
    } else {
      std::printf("  ceiling of this run:");
    }
    const auto checkpoint_bytes = static_cast<uint64_t>(Median(persisted_bytes));
    std::printf(" writing the checkpoint's %.0f MB to one file and syncing it %.3f s\n", checkpoint_bytes / 1e6,
                SequentialWriteSeconds(base + "/ceiling-file", checkpoint_bytes));
    std::printf("  second run, nothing observed since: %.4f s\n", Median(again));
  }

  // 3. Ingest during a publication vs without (after 2 when both run).
  if (wants('3')) {
    std::vector<double> alone, during, ratio, checkpointing;
    for (int r = 0; r < runs; ++r) {
      const double t = kT0 + 3600.0 * sequence;
      const auto quiet_end = Clock::now() + std::chrono::seconds(1);
      alone.push_back(IngestUntil(*store, sequence, t, [&] { return Clock::now() >= quiet_end; }));
      TouchAll(*store, sequence, kT0 + 3600.0 * sequence);
      std::atomic<bool> publishing = true;
      std::thread job([&] {
        (void)store->PublishModels();
        publishing = false;
      });
      during.push_back(IngestUntil(*store, sequence, kT0 + 3600.0 * sequence, [&] { return !publishing; }));
      job.join();
      ratio.push_back(during.back() / alone.back());
      // The checkpoint after the job writes every republished state; ingest goes on meanwhile.
      std::atomic<bool> writing = true;
      std::thread checkpoint([&] {
        (void)store->Checkpoint();
        writing = false;
      });
      checkpointing.push_back(IngestUntil(*store, sequence, kT0 + 3600.0 * sequence, [&] { return !writing; }));
      checkpoint.join();
    }
    std::printf("ingest of 10k-cell scans without a job: %.1fM obs/s, during a 1M-state publication: %.1fM obs/s, "
                "ratio %.2f (medians of %d)\n",
                Median(alone) / 1e6, Median(during) / 1e6, Median(ratio), runs);
    std::printf("  during the checkpoint of the 1M republished states that follows: %.1fM obs/s\n",
                Median(checkpointing) / 1e6);
  }

  // 4. Lossless: per-state update time, extrapolated to 10k cells on 2 cores.
  if (wants('4')) {
    // Every cell dynamic (the worst case), then a building's mix: 1 cell in 20 dynamic.
    const fremen::model::LosslessHistory dynamic = LosslessCell(true), wall = LosslessCell(false);
    std::vector<fremen::model::LosslessHistory> worst(lossless_states, dynamic), office;
    for (int i = 0; i < lossless_states; ++i) office.push_back(i % 20 == 0 ? dynamic : wall);
    const bool all_dynamic = mix != "office", office_mix = mix != "dynamic";
    std::vector<double> worst_s, office_s, transform_s;
    for (int r = 0; r < runs; ++r) {
      if (all_dynamic) transform_s.push_back(TransformOnly(worst));
      if (all_dynamic) worst_s.push_back(LosslessNight(worst));
      if (office_mix) office_s.push_back(LosslessNight(office));
    }
    std::printf("lossless update, 31 days of 5-s slots (%llu slots, the last day new), 2 threads, medians of %d "
                "runs on %d states (target: 10k cells <= 15 s; the paper: < 1 min per night):\n",
                static_cast<unsigned long long>(dynamic.slot_count()), runs, lossless_states);
    if (all_dynamic) {
      std::printf("  every cell dynamic: %.2f ms per state -> 10k cells: %.1f s (ceiling in the same runs, the FFT "
                  "alone: %.2f ms per state -> %.1f s)\n",
                  Median(worst_s) * 1e3, Median(worst_s) * 1e4, Median(transform_s) * 1e3, Median(transform_s) * 1e4);
    }
    if (office_mix) {
      std::printf("  1 cell in 20 dynamic, the rest constant: %.2f ms per state -> 10k cells: %.1f s\n",
                  Median(office_s) * 1e3, Median(office_s) * 1e4);
    }
  }
  return 0;
}
