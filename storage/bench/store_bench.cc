// Load generator for the map store (README.md, "Benchmarks"): prints figures, asserts nothing.
//
// A 1M-cell 3-D grid (100×100×100), default Ω, 2 shards, durable acknowledgements (group commit)
// included: ingest of spatially coherent and of random 10k-cell scans, region prediction of all
// cells from the store, bytes on disk per never-changed and per dynamic cell, and recovery time
// from a crash image taken when the log is at its longest.
//
// Usage: fremen_store_bench [--scans N] [--dir DIR] [--only ingest|region|recovery]
//   DIR: where the maps go (default a temp dir); --only: run one part (e.g. under perf).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <future>
#include <mutex>
#include <random>
#include <string>
#include <thread>

#include "storage/map_store.h"
#include "storage/model/record_codec.h"
#include "storage/wal/wal.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using Clock = std::chrono::steady_clock;
constexpr uint32_t kSide = 100;
constexpr size_t kScanCells = 10000;
// Robots ingesting side by side (each its own writer, at most 4 scans unacknowledged).
constexpr int kWriters = 2;

double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

MapInfo Grid(const std::string& name) {
  MapInfo info;
  info.name = name;
  info.grid.size = {kSide, kSide, kSide};
  info.shards = 2;
  return info;
}

// A scan of 10k cells at time t: a 22×22×21 box at a moving place (coherent) or random cells.
// Cells with x % 5 == 0 open and close every 37 scans; the rest stay free.
ObservationBatch MakeScan(uint64_t i, bool coherent, std::mt19937_64& rng) {
  ObservationBatch b;
  b.writer_id = coherent ? 1 : 2;
  b.sequence = i + 1;
  b.time = 1.7e9 + 5.0 * static_cast<double>(i);
  const bool on = (i / 37) % 2;
  const auto add = [&](uint32_t x, uint32_t y, uint32_t z) {
    b.keys.push_back(MortonKey(x, y, z));
    b.values.push_back(x % 5 == 0 && on ? 1.0f : 0.0f);
  };
  if (coherent) {
    const uint32_t ox = (i * 7) % (kSide - 22), oy = (i * 3) % (kSide - 22), oz = (i * 11) % (kSide - 21);
    for (uint32_t z = oz; z < oz + 21; ++z)
      for (uint32_t y = oy; y < oy + 22; ++y)
        for (uint32_t x = ox; x < ox + 22 && b.keys.size() < kScanCells; ++x) add(x, y, z);
    // Robots send a scan's cells in key order (cheap to sort on the robot, delta-codes well).
    std::vector<size_t> order(b.keys.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t c) { return b.keys[a] < b.keys[c]; });
    ObservationBatch sorted = b;
    for (size_t k = 0; k < order.size(); ++k) {
      sorted.keys[k] = b.keys[order[k]];
      sorted.values[k] = b.values[order[k]];
    }
    return sorted;
  }
  std::uniform_int_distribution<uint32_t> u(0, kSide - 1);
  while (b.keys.size() < kScanCells) add(u(rng), u(rng), u(rng));
  return b;
}

// Submits `scans` scans from `writers` threads (robots: each its own writer id, as the daemon's
// ingest streams submit side by side), each with up to `in_flight` unacknowledged; returns
// cell-observations per second. The store's queue must hold writers × in_flight scans, so that a
// batch that waited for room is never refused.
double Ingest(MapStore& store, uint64_t first, uint64_t scans, bool coherent, int writers, int in_flight) {
  std::mt19937_64 rng(first);
  std::vector<ObservationBatch> prepared;
  for (uint64_t i = first; i < first + scans; ++i) {
    prepared.push_back(MakeScan(i, coherent, rng));
    // The thread that submits it (every writers-th scan) is its writer.
    prepared.back().writer_id = prepared.back().writer_id * 100 + (i - first) % writers;
  }
  std::mutex m;
  std::condition_variable cv;
  uint64_t observations = 0;
  const auto submit_share = [&](int writer) {
    int outstanding = 0;  // this writer's, guarded by m
    for (size_t i = writer; i < prepared.size(); i += writers) {
      ObservationBatch& b = prepared[i];
      {
        std::unique_lock lock(m);
        cv.wait(lock, [&] { return outstanding < in_flight; });
        ++outstanding;
      }
      // Backpressure as a streaming handler meets it: wait until the queue has room, then submit.
      std::promise<void> room;
      store.OnRoom(b.observation_count(), [&room] { room.set_value(); });
      room.get_future().wait();
      const absl::Status s = store.Submit(std::move(b), [&](absl::StatusOr<BatchAck> ack) {
        std::lock_guard l(m);
        if (ack.ok()) observations += ack->accepted;
        --outstanding;
        cv.notify_all();
      });
      if (!s.ok()) {
        std::fprintf(stderr, "submit: %s\n", std::string(s.message()).c_str());
        std::exit(1);
      }
    }
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return outstanding == 0; });
  };
  const auto start = Clock::now();
  std::vector<std::thread> threads;
  for (int w = 0; w < writers; ++w) threads.emplace_back(submit_share, w);
  for (std::thread& t : threads) t.join();
  return observations / Seconds(start, Clock::now());
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Recovery: a crash image taken when the log is at its longest (just before a checkpoint), opened
// 5 times, each from a fresh copy (the page cache warm: the disk is not what is measured).
void Recovery(const std::string& base, uint64_t scans) {
  StoreOptions never;
  never.checkpoint_log_bytes = UINT64_MAX;
  auto m = MapStore::Open(Grid("recover"), base + "/recover", never);
  if (!m.ok()) return (void)std::fprintf(stderr, "%s\n", std::string(m.status().message()).c_str());
  (void)Ingest(**m, 0, scans, true, kWriters, 4);
  const uint64_t log_bytes = (*m)->Stats().log_bytes;
  // The files as they are while the store is open (a crash image): closing would checkpoint.
  std::filesystem::copy(base + "/recover", base + "/crash-image", std::filesystem::copy_options::recursive);
  m->reset();
  std::vector<double> seconds, reading;
  bool ok = true;
  for (int rep = 0; rep < 5; ++rep) {
    const std::string image = base + "/recover-image";
    std::filesystem::remove_all(image);
    std::filesystem::copy(base + "/crash-image", image, std::filesystem::copy_options::recursive);
    // The ceiling, interleaved with the recoveries: what any recovery must do at least, read the
    // log and check every record's CRC, with nothing decoded or applied.
    auto start = Clock::now();
    uint64_t records = 0;
    auto read = ReplayWal(image + "/wal", 0, [&](uint64_t, std::span<const uint8_t>) {
      ++records;
      return absl::OkStatus();
    });
    reading.push_back(Seconds(start, Clock::now()));
    ok = ok && read.ok() && records > 0;
    start = Clock::now();
    auto recovered = MapStore::Open(Grid("recover"), image, never);
    seconds.push_back(Seconds(start, Clock::now()));
    ok = ok && recovered.ok();
  }
  std::printf("recovery from a crash image with %.0f MB of log (%llu scans): %.2f s (median of 5, %.2f-%.2f; "
              "target <= 1 s) %s\n",
              log_bytes / 1e6, static_cast<unsigned long long>(scans), Median(seconds),
              *std::min_element(seconds.begin(), seconds.end()), *std::max_element(seconds.begin(), seconds.end()),
              ok ? "" : "FAILED");
  std::printf("  ceiling of this run: reading the log and checking its CRCs alone %.2f s (median of 5); "
              "the recovery takes %.1fx that\n",
              Median(reading), Median(seconds) / Median(reading));
}

}  // namespace
}  // namespace fremen::storage

int main(int argc, char** argv) {
  using namespace fremen::storage;
  uint64_t scans = 2000;
  std::string base, only;
  for (int i = 1; i < argc; i += 2) {
    const bool has_value = i + 1 < argc;
    if (has_value && !std::strcmp(argv[i], "--scans")) {
      scans = std::strtoull(argv[i + 1], nullptr, 10);
    } else if (has_value && !std::strcmp(argv[i], "--dir")) {
      base = argv[i + 1];
    } else if (has_value && !std::strcmp(argv[i], "--only") &&
               (!std::strcmp(argv[i + 1], "ingest") || !std::strcmp(argv[i + 1], "region") ||
                !std::strcmp(argv[i + 1], "recovery"))) {
      only = argv[i + 1];
    } else {
      std::fprintf(stderr, "usage: fremen_store_bench [--scans N] [--dir DIR] [--only ingest|region|recovery]\n");
      return 2;
    }
  }
  const auto runs = [&only](const char* part) { return only.empty() || only == part; };
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  fremen::testing::TempDir temp;
  if (base.empty()) base = temp.path();
  if (only == "recovery") return Recovery(base, scans), 0;

  StoreOptions options;
  options.max_queued_observations = kWriters * 4 * kScanCells;
  auto store = MapStore::Open(Grid("bench"), base + "/grid", options);
  if (!store.ok()) return std::fprintf(stderr, "%s\n", std::string(store.status().message()).c_str()), 1;
  MapStore& map = **store;

  // Warm up: a robot's first sweep observes every cell once, plane by plane, so the ingest figures
  // measure steady state, not the growth of the map.
  for (uint32_t z = 0; z < kSide; ++z) {
    ObservationBatch plane;
    plane.writer_id = 3;
    plane.sequence = z + 1;
    plane.time = 1.7e9 - 1000.0 + z;
    for (uint32_t y = 0; y < kSide; ++y) {
      for (uint32_t x = 0; x < kSide; ++x) {
        plane.keys.push_back(MortonKey(x, y, z));
        plane.values.push_back(0.0f);
      }
    }
    std::sort(plane.keys.begin(), plane.keys.end());
    (void)map.Write(std::move(plane));
  }
  std::vector<double> coherent, random;
  for (int rep = 0; rep < 3 && runs("ingest"); ++rep) {
    coherent.push_back(Ingest(map, 1'000'000 + rep * scans, scans, true, kWriters, 4));
    random.push_back(Ingest(map, 2'000'000 + rep * scans, scans / 2, false, kWriters, 4));
  }
  if (runs("ingest")) {
    std::printf("ingest, coherent 10k-cell scans from %d writers, durable acks: %.1fM cell-obs/s (median of 3; "
                "target >= 20M)\n", kWriters,
                Median(coherent) / 1e6);
    std::printf("ingest, random 10k-cell scans from %d writers, durable acks:   %.1fM cell-obs/s (median of 3; "
                "target >= 5M)\n", kWriters,
                Median(random) / 1e6);
    if (only == "ingest") return 0;
  }

  (void)map.PublishModels();
  std::vector<double> region;
  std::vector<float> out;
  const CellBox all{{0, 0, 0}, {kSide, kSide, kSide}};
  for (int rep = 0; rep < 15; ++rep) {
    const auto start = Clock::now();
    (void)map.PredictBox(all, 1.7e9 + 3600.0 * rep, {}, out);
    region.push_back(all.cell_count() / Seconds(start, Clock::now()));
    if (getenv("FREMEN_BENCH_VERBOSE")) std::printf("  region run %d: %.0fM cells/s\n", rep, region.back() / 1e6);
  }
  std::printf("region prediction of all 1M cells from the store: %.0fM cells/s (median of 15; target >= 200M)\n",
              Median(region) / 1e6);
  if (only == "region") return 0;

  (void)map.Checkpoint();
  const MapStats stats = map.Stats();
  std::printf("map: %llu states, %llu dynamic, %.1f MB on disk, %.1f MB in memory\n",
              static_cast<unsigned long long>(stats.totals.states),
              static_cast<unsigned long long>(stats.totals.dynamic_states), stats.totals.disk_bytes / 1e6,
              stats.totals.memory_bytes / 1e6);

  // Bytes on disk: a map of never-changed cells, and one whose every cell is dynamic.
  for (bool dynamic : {false, true}) {
    auto m = MapStore::Open(Grid(dynamic ? "dyn" : "static"), base + (dynamic ? "/dyn" : "/static"), {});
    std::mt19937_64 rng(1);
    for (uint64_t i = 0; i < 200; ++i) {
      ObservationBatch b = MakeScan(i, false, rng);
      b.keys.clear();
      b.values.clear();
      for (uint32_t k = 0; k < 5000; ++k) {
        const uint64_t cell = (i * 5000 + k) % 100000;  // each cell seen 10 times
        b.keys.push_back(MortonKey(cell % kSide, cell / kSide % kSide, cell / (kSide * kSide)));
        b.values.push_back(dynamic ? static_cast<float>((i / 20 + k) % 2) : 0.0f);
      }
      (void)(*m)->Write(std::move(b));
    }
    (void)(*m)->Checkpoint();
    const MapStats s = (*m)->Stats();
    const double per_cell = static_cast<double>(s.totals.disk_bytes) / s.totals.states;
    if (dynamic) {
      const size_t record = fremen::model::EncodeStateModel((*m)->Snapshot(MortonKey(1, 0, 0))->model.value()).size();
      std::printf("disk per dynamic cell: %.0f B, %.2fx its %zu-byte record (target <= 1.5x)\n", per_cell,
                  per_cell / record, record);
    } else {
      std::printf("disk per never-changed cell: %.1f B (target <= 32)\n", per_cell);
    }
  }

  Recovery(base, scans);
  return 0;
}
