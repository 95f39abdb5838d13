// Benchmarks of the batch kernels against their per-core targets (docs/performance.md, "Targets"), at
// the default Ω (K = 24) and L = 5, on data sizes far beyond the caches (the machine: 2 cores, 32 MiB
// L3, ~50 GB/s read+write).
//
//   update, cells sharing one scan time   dense ≥ 50M cell-obs/s, random ≥ 20M   (BM_Update*)
//   region prediction of 1M cells         l = 2 ≥ 300M/s, l = 5 ≥ 150M/s         (BM_Predict*)
//   publication (order choice + top L)    ≥ 2M states/s                          (BM_Publish)
//   memory per state                      never changed 16 B, working record ≤ 16·K + 64,
//                                         compact P ≤ 64                         (BM_MemoryPerState)
// items_per_second is cell-observations (update), cells (prediction) or states (publication).
// BM_Ceiling* measure the machine's own limits in the same run (the machine is shared and noisy:
// judge the kernels as a share of these). /threads:2 variants give the 2-core figures.
// Shared fixtures are built once and kept for the whole run (~5.2 GB: the 10M-cell arena, 4.5 GB).
// Run: fremen_model_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "storage/model/kernels/compact_models.h"
#include "storage/model/kernels/model_columns.h"
#include "storage/model/kernels/order_error_table.h"
#include "storage/model/persistence.h"
#include "storage/model/kernels/publication.h"
#include "storage/model/kernels/record_arena.h"
#include "storage/model/kernels/region_predict.h"
#include "storage/model/kernels/scan_update.h"
#include "storage/model/static_state.h"

namespace fremen::model {
namespace {

constexpr int kL = 5;
constexpr size_t kArenaCells = 10'000'000;  // the random-update map: 4.5 GB of working records
constexpr size_t kScanCells = 1 << 20;      // cells per scan, and cells per prediction/publication
constexpr double kT0 = 1.7e9;

const PeriodSet& Periods() {
  static const PeriodSet periods = PeriodSet::Default();
  return periods;
}

// Records of cells that have seen ~1000 observations over a week; the first kScanCells have a
// random spectrum, so that publication ranks realistic, distinct amplitudes.
RecordArena& BigArena() {
  static RecordArena* arena = [] {
    auto* a = new RecordArena(Periods().size(), kArenaCells);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.05f, 0.05f);
    for (size_t i = 0; i < a->size(); ++i) {
      a->header(i) = {kT0 - 7 * 86400.0, kT0, 300.0, 1000, 0};
      if (i < kScanCells) {
        float* body = a->body(i);
        for (size_t j = 0; j < Periods().size() * kRealsPerPeriod; ++j) body[j] = u(rng);
      }
    }
    return a;
  }();
  return *arena;
}

std::vector<float> RandomValues(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<float> values(n);
  for (float& v : values) v = static_cast<float>(rng() & 1);
  return values;
}

// About kScanCells distinct cells of the big arena, ascending.
const std::vector<uint32_t>& SortedRandomCells() {
  static const std::vector<uint32_t> cells = [] {
    std::mt19937_64 rng(2);
    std::vector<uint32_t> out;
    out.reserve(kScanCells + kScanCells / 8);
    const uint64_t threshold = static_cast<uint64_t>(static_cast<double>(kScanCells) / kArenaCells * 4294967296.0);
    for (uint32_t c = 0; c < kArenaCells; ++c) {
      if ((rng() & 0xffffffffu) < threshold) out.push_back(c);
    }
    return out;
  }();
  return cells;
}

const std::vector<uint32_t>& ShuffledRandomCells() {
  static const std::vector<uint32_t> cells = [] {
    std::vector<uint32_t> out = SortedRandomCells();
    std::shuffle(out.begin(), out.end(), std::mt19937_64(3));
    return out;
  }();
  return cells;
}

// One scan per iteration, each a minute after the previous one; the phasor tables are built inside
// the timed loop (they are part of the cost of a scan, if a negligible one).
template <typename Kernel>
void RunScans(benchmark::State& state, size_t cells_per_scan, Kernel kernel) {
  double t = kT0;
  for (auto _ : state) {
    t += 60;
    const PhasorTable table(Periods(), t);
    kernel(table, ScanPhasors<float>(table));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * cells_per_scan));
}

// With several threads (->Threads(2): the 2-core figures), each takes its own share of the scan's
// cells, as the shards of a map would; cells are distinct and records line-aligned, so no two threads
// touch a cache line in common.
template <typename T>
std::span<const T> ThreadShare(const benchmark::State& state, std::span<const T> all) {
  const size_t share = all.size() / state.threads();
  return all.subspan(share * state.thread_index(), share);
}

void BM_UpdateDense(benchmark::State& state) {
  RecordArena& arena = BigArena();
  const size_t n = static_cast<size_t>(state.range(0)) / state.threads();
  const size_t first = n * state.thread_index();
  const std::vector<float> values = RandomValues(n, 4);
  RunScans(state, n, [&](const PhasorTable&, const ScanPhasors<float>& p) { ApplyDenseScan(arena, p, first, values); });
}
// 16k cells (7 MiB) stay in L3: the compute bound. 1M cells (448 MiB): the memory bound.
BENCHMARK(BM_UpdateDense)->Arg(16 << 10)->Arg(kScanCells)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateDense)->Arg(kScanCells)->Threads(2)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_UpdateRandom(benchmark::State& state) {
  RecordArena& arena = BigArena();
  const auto cells = ThreadShare<uint32_t>(state, state.range(0) ? SortedRandomCells() : ShuffledRandomCells());
  const std::vector<float> values = RandomValues(cells.size(), 5);
  state.SetLabel(state.range(0) ? "sorted" : "unsorted");
  RunScans(state, cells.size(),
           [&](const PhasorTable&, const ScanPhasors<float>& p) { ApplyScan(arena, p, cells, values); });
}
BENCHMARK(BM_UpdateRandom)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateRandom)->Arg(0)->Arg(1)->Threads(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// The same loop without ApplyScan's prefetching: what the prefetch buys.
void BM_UpdateRandomNoPrefetch(benchmark::State& state) {
  RecordArena& arena = BigArena();
  const auto& cells = state.range(0) ? SortedRandomCells() : ShuffledRandomCells();
  const std::vector<float> values = RandomValues(cells.size(), 5);
  state.SetLabel(state.range(0) ? "sorted" : "unsorted");
  RunScans(state, cells.size(), [&](const PhasorTable&, const ScanPhasors<float>& p) {
    for (size_t i = 0; i < cells.size(); ++i)
      FoldObservation(arena.header(cells[i]), arena.body(cells[i]), p, values[i]);
  });
}
BENCHMARK(BM_UpdateRandomNoPrefetch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Compact models of kScanCells random cells: L components each, selected orders 0..L mixed.
const CompactModels& Models() {
  static const CompactModels* models = [] {
    const size_t n = kScanCells;
    auto* m = new CompactModels(kL, n);
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (size_t i = 0; i < n; ++i) {
      CompactModelHeader& h = m->header(i);
      h = {0.2f + 0.6f * u(rng), static_cast<uint8_t>(rng() % (kL + 1)), 1, kL};
      for (int j = 0; j < kL; ++j) {
        m->k(i)[j] = static_cast<uint16_t>(rng() % Periods().size());
        m->a(i)[j] = 0.2f * u(rng) - 0.1f;
        m->b(i)[j] = 0.2f * u(rng) - 0.1f;
      }
    }
    return m;
  }();
  return *models;
}

// The fused benchmark scans the first kScoredCells cells of the arena (its ~half of the random scan),
// so that its published models and error counters (124 B per cell) fit the memory budget.
constexpr size_t kScoredCells = kArenaCells / 2;

const std::vector<uint32_t>& ScoredCells(bool sorted) {
  static const auto subset = [](const std::vector<uint32_t>& all) {
    std::vector<uint32_t> out;
    std::copy_if(all.begin(), all.end(), std::back_inserter(out), [](uint32_t c) { return c < kScoredCells; });
    return out;
  };
  static const std::vector<uint32_t> sorted_cells = subset(SortedRandomCells());
  static const std::vector<uint32_t> shuffled_cells = subset(ShuffledRandomCells());
  return sorted ? sorted_cells : shuffled_cells;
}

OrderErrorTable& ScoredErrors() {
  static OrderErrorTable* errors = new OrderErrorTable(kL, kScoredCells);
  return *errors;
}

CompactModels& ScoredModels() {
  static CompactModels* models = [] {
    auto* m = new CompactModels(kL, kScoredCells);
    const CompactModels& sample = Models();
    for (size_t i = 0; i < kScoredCells; ++i) {
      std::copy_n(sample.record(i % kScanCells), m->stride(), reinterpret_cast<std::byte*>(&m->header(i)));
    }
    return m;
  }();
  return *models;
}

// The ingest pass with the prequential scoring of every cell (all published) at orders 0..5.
void BM_ScoreAndUpdateRandom(benchmark::State& state) {
  RecordArena& arena = BigArena();
  const auto& cells = ScoredCells(state.range(0) != 0);
  const std::vector<float> values = RandomValues(cells.size(), 5);
  const ScanScoring scoring{&ScoredModels(), &ScoredErrors(), ErrorCriterion::kThreshold, 7 * 86400.0};
  state.SetLabel(state.range(0) ? "sorted" : "unsorted");
  RunScans(state, cells.size(), [&](const PhasorTable& table, const ScanPhasors<float>& p) {
    ScoreAndApplyScan(arena, scoring, table, p, cells, values);
  });
}
BENCHMARK(BM_ScoreAndUpdateRandom)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The scoring alone (P and error records only).
void BM_ScoreRandom(benchmark::State& state) {
  const auto& cells = ScoredCells(state.range(0) != 0);
  const std::vector<float> values = RandomValues(cells.size(), 5);
  const ScanScoring scoring{&ScoredModels(), &ScoredErrors(), ErrorCriterion::kThreshold, 7 * 86400.0};
  state.SetLabel(state.range(0) ? "sorted" : "unsorted");
  RunScans(state, cells.size(),
           [&](const PhasorTable& table, const ScanPhasors<float>&) { ScoreScan(scoring, table, cells, values); });
}
BENCHMARK(BM_ScoreRandom)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Region prediction of kScanCells cells at one time; range(0) = order (-1: each cell's own, mixed),
// a new time per iteration (the per-query table is part of the cost).
template <typename Out, typename Predict>
void RunPredictions(benchmark::State& state, Predict predict) {
  const CompactModels& models = Models();
  std::vector<Out> out(models.size());
  const int order = static_cast<int>(state.range(0));
  double t = kT0;
  for (auto _ : state) {
    t += 1;
    predict(models, PhasorTable(Periods(), t), order, out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * models.size()));
  state.SetLabel(order < 0 ? "own orders, mixed 0..5" : "l = " + std::to_string(order));
}

void BM_PredictFloat(benchmark::State& state) {
  RunPredictions<float>(state, [](const CompactModels& m, const PhasorTable& p, int order, float* out) {
    PredictRegion(m, p, order, out);
  });
}
BENCHMARK(BM_PredictFloat)->Arg(2)->Arg(5)->Arg(-1)->Unit(benchmark::kMicrosecond);

void BM_PredictU8(benchmark::State& state) {
  RunPredictions<uint8_t>(state, [](const CompactModels& m, const PhasorTable& p, int order, uint8_t* out) {
    PredictRegionU8(m, p, order, out);
  });
}
BENCHMARK(BM_PredictU8)->Arg(2)->Arg(5)->Arg(-1)->Unit(benchmark::kMicrosecond);

// The listed form a shard's box query runs, a brick (512 records) at a time; range(1) = 1: the records
// shuffled within each brick, the worst case of a box whose states were promoted in no spatial order
// (memory-bound: each record is a cache miss the prefetcher cannot foresee), 0: in order.
void BM_PredictListed(benchmark::State& state) {
  const bool shuffled = state.range(1) != 0;
  std::vector<uint32_t> records(Models().size());
  for (size_t i = 0; i < records.size(); ++i) records[i] = static_cast<uint32_t>(i);
  std::mt19937_64 rng(3);
  for (size_t b = 0; shuffled && b < records.size(); b += 512) {
    std::shuffle(records.begin() + b, records.begin() + std::min(records.size(), b + 512), rng);
  }
  RunPredictions<float>(state, [&](const CompactModels& m, const PhasorTable& p, int order, float* out) {
    for (size_t b = 0; b < records.size(); b += 512) {
      PredictRecords(m, std::span(records).subspan(b, std::min<size_t>(512, records.size() - b)), p, order, out + b);
    }
  });
  const int order = static_cast<int>(state.range(0));
  state.SetLabel((order < 0 ? std::string("own orders, mixed 0..5") : "l = " + std::to_string(order)) +
                 (shuffled ? ", shuffled in bricks" : ", in order"));
}
BENCHMARK(BM_PredictListed)->ArgsProduct({{2, 5, -1}, {0, 1}})->Unit(benchmark::kMicrosecond);

// The form a region reads a shard's published models in since they are copied brick by brick
// (storage/brick_models.h): the same models as columns at their own orders, predicted as bytes in
// runs of range(0) models (a brick's dynamic cells: 60 in fremen_query_load's map), each run at its
// highest own order; range(1) models (all of Models(), 1M, as BM_PredictU8/-1 and
// BM_PredictListed/-1/*, or 2^17, about fremen_query_load's box: 7 MB, which the cache holds), on
// path range(2) (ColumnsPath: 0 AVX-512, 1 AVX2, 2 scalar; skipped where the machine has not it).
void BM_PredictColumnsU8(benchmark::State& state) {
  const size_t run = static_cast<size_t>(state.range(0)), count = static_cast<size_t>(state.range(1));
  const auto path = static_cast<ColumnsPath>(state.range(2));
  const char* const path_names[] = {"AVX-512", "AVX2", "scalar"};
  if (!PredictColumnsCan(path, PeriodSet::Default().size())) {
    state.SkipWithError((std::string(path_names[state.range(2)]) + ": not on this machine").c_str());
    return;
  }
  const auto columns = std::make_unique<ModelColumns>(kL);
  columns->Resize(count);
  for (size_t i = 0; i < count; ++i) columns->SetZero(i, Models(), i);
  std::vector<int> terms;
  for (size_t first = 0; first < columns->size(); first += run) {
    int highest = 0;
    for (size_t i = first; i < std::min(columns->size(), first + run); ++i) {
      highest = std::max<int>(highest, columns->order()[i]);
    }
    terms.push_back(highest);
  }
  RunPredictions<uint8_t>(state, [&](const CompactModels&, const PhasorTable& p, int, uint8_t* out) {
    for (size_t first = 0, r = 0; first < columns->size(); first += run, ++r) {
      PredictColumnsOn(path, *columns, first, std::min(run, columns->size() - first), terms[r], p, out + first);
    }
  });
  // RunPredictions counts Models().size() a call.
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * count));
  state.SetLabel(std::string(path_names[state.range(2)]) + ", own orders, mixed 0..5, runs of " + std::to_string(run) +
                 ", " + std::to_string(count) + " models");
}
BENCHMARK(BM_PredictColumnsU8)
    ->ArgsProduct({{60, 512}, {1 << 17, 1 << 20}, {0, 1, 2}})
    ->Unit(benchmark::kMicrosecond);

// Order choice + top-L publication of kScanCells states (errors choose orders 0..5 at random).
void BM_Publish(benchmark::State& state) {
  const RecordArena& arena = BigArena();
  OrderErrorTable errors(kL, kScanCells);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < kScanCells; ++i) {
    OrderErrors e(kL);
    std::vector<double> sums(kL + 1);
    for (double& s : sums) s = u(rng);
    e.Restore(kT0, 1.0, sums);
    errors.Set(i, e);
  }
  CompactModels models(kL, kScanCells);
  const Publisher publisher(Periods(), kL);
  const OrderRule rule{static_cast<OrderSelection>(state.range(0))};
  for (auto _ : state) {
    publisher.PublishRange(arena, errors, 0, kScanCells, models, rule);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kScanCells));
}
// Arg: the OrderSelection (0 margin, 1 paper, 2 weighted: L + 1 exp per state).
BENCHMARK(BM_Publish)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The single-state path for comparison: PublishedModel::FromSpectrum of a CompactSpectrum.
void BM_PublishSingleStateReference(benchmark::State& state) {
  const RecordArena& arena = BigArena();
  constexpr size_t kStates = 1 << 16;
  std::vector<CompactSpectrum> spectra(kStates, CompactSpectrum(Periods().size()));
  for (size_t i = 0; i < kStates; ++i) arena.Load(i, spectra[i]);
  for (auto _ : state) {
    for (const CompactSpectrum& s : spectra) {
      benchmark::DoNotOptimize(PublishedModel::FromSpectrum(s, Periods(), kL, 3));
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kStates));
}
BENCHMARK(BM_PublishSingleStateReference)->Unit(benchmark::kMillisecond);

// This machine's limits in the same run (docs/performance.md: compare as ratios inside one run, the
// machine is shared): a vectorised read-modify-write stream over the dense benchmark's 448 MiB, in
// records/s of 448 B; and one word rewritten per cache line of the random benchmark's records
// (prefetched), in records/s. A kernel cannot beat these. Both XOR with a zero the compiler cannot see,
// so that the records stay intact for the other benchmarks.
uint32_t OpaqueZero() {
  uint32_t zero = 0;
  benchmark::DoNotOptimize(zero);
  return zero;
}

void BM_CeilingDenseReadModifyWrite(benchmark::State& state) {
  RecordArena& arena = BigArena();
  const size_t words = kScanCells * arena.stride() / sizeof(uint32_t);
  auto* data = reinterpret_cast<uint32_t*>(arena.body(0));
  const uint32_t zero = OpaqueZero();
  for (auto _ : state) {
    for (size_t i = 0; i < words; ++i) data[i] ^= zero;
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kScanCells));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * kScanCells * arena.stride() * 2));
}
BENCHMARK(BM_CeilingDenseReadModifyWrite)->Unit(benchmark::kMillisecond);

void BM_CeilingRandomTouch(benchmark::State& state) {
  RecordArena& arena = BigArena();
  const auto& cells = state.range(0) ? SortedRandomCells() : ShuffledRandomCells();
  const size_t stride = arena.stride();
  const uint32_t zero = OpaqueZero();
  state.SetLabel(state.range(0) ? "sorted" : "unsorted");
  for (auto _ : state) {
    for (size_t i = 0; i < cells.size(); ++i) {
      if (i + 8 < cells.size()) PrefetchForWrite(arena.record(cells[i + 8]), stride);
      auto* record = reinterpret_cast<uint32_t*>(arena.body(cells[i]));
      for (size_t w = 0; w < stride / sizeof(uint32_t); w += 64 / sizeof(uint32_t)) record[w] ^= zero;
    }
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * cells.size()));
}
BENCHMARK(BM_CeilingRandomTouch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Bytes per state, as counters (and printed once): the targets are 16, ≤ 16·K + 64 = 448 and ≤ 64.
void BM_MemoryPerState(benchmark::State& state) {
  const size_t k = Periods().size();
  const double never_changed = sizeof(StaticState);
  const double working_record = RecordArena::StrideFor(k);
  const double compact_p = CompactModels::StrideFor(kL);
  const double errors = OrderErrorTable::StrideFor(kL);
  const double persistence = sizeof(Persistence);
  for (auto _ : state) benchmark::DoNotOptimize(k);
  state.counters["never_changed_B"] = never_changed;
  state.counters["working_record_B"] = working_record;
  state.counters["compact_P_B"] = compact_p;
  state.counters["order_errors_B"] = errors;
  state.counters["persistence_B"] = persistence;
  state.counters["dynamic_total_B"] = working_record + compact_p + errors + persistence;
  static bool printed = false;
  if (!printed) {
    printed = true;
    std::printf(
        "memory per state (K = %zu, L = %d): never changed %.0f B; dynamic: working record %.0f B (target <= %zu), "
        "compact P %.0f B (target <= 64), order errors %.0f B, persistence %.0f B, total %.0f B\n",
        k, kL, never_changed, working_record, 16 * k + 64, compact_p, errors, persistence,
        working_record + compact_p + errors + persistence);
  }
}
BENCHMARK(BM_MemoryPerState)->Iterations(1);

}  // namespace
}  // namespace fremen::model
