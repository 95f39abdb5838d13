// fremen_ingest_load: the ingest load generator (README.md, "Benchmarks"). Against a running
// fremend it streams scans of grid cells by index (default: 4 streams of 10k-cell scans, at most 64
// unacknowledged batches per stream, acknowledged only once durable) and prints the cell
// observations per second acknowledged (the median of --repetitions windows), the batch rate and
// the acknowledgement latency. It first prints what one scan costs to encode and decode (the
// CellIndices layout), and finally the latency of single-state Predict calls when the daemon serves
// QueryService (client/bench/fremen_query_load is the full query benchmark).
//
// The map (default "ingest-load", a 100×100×100 grid = 1M cells) is created when missing. Each
// run writes as new writers (random ids), so runs against the same map are never duplicates.
//
// --history-states N streams histories instead (IngestRequest.history, a time per observation)
// into a generic map (default "ingest-load-history"): each batch --cells observations, a minute
// apart, of one state per stream (N = 1: one door's log uploaded) or of N states per stream in
// turn. Printed beside it, as the ceiling of the same run: how fast one core does the least
// arithmetic of such an observation (the phasors of the default 24 periods at its time, once per
// distinct time, and the fold into one state), which no batching amortises.
//
// Uses only the API (fremen_proto + gRPC), as any client does, on gRPC's callback API
// (client/bench/windowed_ingest.h); the main thread samples the counters.
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <cmath>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "CLI/CLI.hpp"
#include "base/compact_scan.h"
#include "client/bench/load_stats.h"
#include "client/bench/windowed_ingest.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"

namespace {

namespace v1 = fremen::v1;
using fremen::bench::Clock;
using fremen::bench::Median;
using fremen::bench::Quantile;
using fremen::bench::Seconds;

constexpr double kT0 = 1.7e9;
constexpr double kScanInterval = 0.1;  // seconds between a robot's scans (10 Hz)
constexpr int kScansPerStream = 16;    // distinct scans each stream cycles through

struct Options {
  std::string address = "127.0.0.1:50051";
  std::string map = "ingest-load";
  std::string token;
  uint32_t grid = 100;  // cells along each axis of the map, when created
  int streams = 4;
  uint32_t cells = 10000;  // per scan
  int window = 64;         // unacknowledged batches per stream (the C++ and Python clients' default)
  double warmup = 2;       // seconds before the first window
  double seconds = 5;      // per repetition
  int repetitions = 5;
  int predict_calls = 5000;
  // > 0: each stream sends exactly this many batches, waits for their acknowledgements and the run
  // ends (no windows, no encoding measurement): a fixed workload whose instructions
  // scripts/ingest-instructions.sh counts.
  uint64_t batches = 0;
  // "cells": CellObservations (x, y, z arrays and floats); "compact": CompactCells (index gaps and
  // occupied bits).
  std::string encoding = "cells";
  uint32_t history_states = 0;  // 0: scans of cells; else histories of this many states per stream
};

constexpr double kHistoryInterval = 60;  // seconds between a history's observations of a state

class Client {
 public:
  explicit Client(const Options& o)
      : o_(o),
        channel_(grpc::CreateChannel(o.address, grpc::InsecureChannelCredentials())),
        maps_(v1::MapService::NewStub(channel_)),
        query_(v1::QueryService::NewStub(channel_)) {}

  // A context naming the map (for proxies) and carrying the token.
  std::unique_ptr<grpc::ClientContext> Context() const {
    auto context = std::make_unique<grpc::ClientContext>();
    context->AddMetadata("x-fremen-map", o_.map);
    if (!o_.token.empty()) context->AddMetadata("authorization", "Bearer " + o_.token);
    return context;
  }
  // A new channel per stream: one HTTP/2 connection each, as separate robots have.
  std::shared_ptr<grpc::Channel> NewChannel() const {
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    return grpc::CreateCustomChannel(o_.address, grpc::InsecureChannelCredentials(), args);
  }

  bool EnsureMap() const;
  void Predict() const;

 private:
  const Options o_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::QueryService::Stub> query_;
};

bool Client::EnsureMap() const {
  v1::GetMapRequest get;
  get.set_map(o_.map);
  v1::GetMapResponse got;
  grpc::Status status = maps_->GetMap(Context().get(), get, &got);
  const v1::MapKind kind = o_.history_states > 0 ? v1::MAP_KIND_GENERIC : v1::MAP_KIND_GRID;
  if (status.ok() && got.map().kind() != kind) {
    std::fprintf(stderr, "map %s is not a %s map; choose another --map\n", o_.map.c_str(),
                 kind == v1::MAP_KIND_GRID ? "grid" : "generic");
    return false;
  }
  if (status.ok() && kind == v1::MAP_KIND_GENERIC) {
    std::printf("map %s: generic, %u shards\n", o_.map.c_str(), got.map().shards());
    return true;
  }
  if (status.ok()) {
    const v1::GridSize& size = got.map().grid().size();
    if (size.x() != o_.grid || size.y() != o_.grid || size.z() != o_.grid) {
      std::fprintf(stderr, "map %s is %u×%u×%u cells, not --grid %u cubed; choose another --map\n", o_.map.c_str(),
                   size.x(), size.y(), size.z(), o_.grid);
      return false;
    }
    std::printf("map %s: %u×%u×%u cells, %u shards\n", o_.map.c_str(), size.x(), size.y(), size.z(),
                got.map().shards());
    return true;
  }
  if (status.error_code() != grpc::StatusCode::NOT_FOUND) {
    std::fprintf(stderr, "GetMap %s: %s\n", o_.map.c_str(), status.error_message().c_str());
    return false;
  }
  v1::CreateMapRequest create;
  v1::Map& map = *create.mutable_map();
  map.set_name(o_.map);
  map.set_kind(kind);
  if (kind == v1::MAP_KIND_GRID) {
    map.mutable_grid()->set_resolution(0.05);
    map.mutable_grid()->mutable_size()->set_x(o_.grid);
    map.mutable_grid()->mutable_size()->set_y(o_.grid);
    map.mutable_grid()->mutable_size()->set_z(o_.grid);
  }
  v1::CreateMapResponse created;
  status = maps_->CreateMap(Context().get(), create, &created);
  if (!status.ok()) {
    std::fprintf(stderr, "CreateMap %s: %s\n", o_.map.c_str(), status.error_message().c_str());
    return false;
  }
  if (kind == v1::MAP_KIND_GENERIC) {
    std::printf("created generic map %s, %u shards\n", o_.map.c_str(), created.map().shards());
    return true;
  }
  std::printf("created map %s: %u×%u×%u cells, %u shards\n", o_.map.c_str(), o_.grid, o_.grid, o_.grid,
              created.map().shards());
  return true;
}

// Scan k of a stream: `cells` consecutive cells of the grid (x fastest), starting at a layer of its
// own, as a robot's sweep covers a neighbourhood; values 0/1.
v1::IngestRequest MakeScan(const Options& o, int stream, int k, std::mt19937_64& random) {
  v1::IngestRequest request;
  request.set_map(o.map);
  v1::CellIndices& cells = *request.mutable_cells()->mutable_cells();
  cells.mutable_x()->Reserve(o.cells);
  cells.mutable_y()->Reserve(o.cells);
  cells.mutable_z()->Reserve(o.cells);
  const uint64_t layer = uint64_t{o.grid} * o.grid;
  const uint64_t first = (static_cast<uint64_t>(stream * kScansPerStream + k) * o.cells) % (layer * o.grid);
  std::vector<uint64_t> indices;
  for (uint64_t i = first; i < first + o.cells; ++i) {
    const uint64_t c = i % (layer * o.grid);
    indices.push_back(c);
    cells.add_x(static_cast<uint32_t>(c % o.grid));
    cells.add_y(static_cast<uint32_t>(c / o.grid % o.grid));
    cells.add_z(static_cast<uint32_t>(c / layer));
    request.mutable_cells()->add_values(random() % 4 == 0 ? 1.0f : 0.0f);
  }
  if (o.encoding != "compact") return request;
  // The same cells and values, sorted by index (a scan that wraps past the grid's last cell starts
  // again at 0), in the compact form.
  std::vector<float> values(request.cells().values().begin(), request.cells().values().end());
  std::vector<size_t> order(indices.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return indices[a] < indices[b]; });
  std::vector<uint64_t> sorted_indices;
  std::vector<float> sorted_values;
  for (size_t i : order) {
    sorted_indices.push_back(indices[i]);
    sorted_values.push_back(values[i]);
  }
  v1::CompactCells& compact = *request.mutable_compact();  // clears cells
  compact.set_indices(fremen::EncodeIndexGaps(sorted_indices));
  compact.set_occupied(fremen::PackOccupiedBits(sorted_values));
  return request;
}

// History k of a stream: --cells observations of the stream's --history-states states in turn, a
// minute apart per state, a door's values (open for a stretch now and then); the writer shifts the
// times of each batch it sends past the previous one's.
v1::IngestRequest MakeHistory(const Options& o, int stream, std::mt19937_64& random) {
  v1::IngestRequest request;
  request.set_map(o.map);
  v1::HistoryObservations& h = *request.mutable_history();
  h.mutable_times()->Reserve(o.cells);
  h.mutable_values()->Reserve(o.cells);
  const uint64_t first_id = static_cast<uint64_t>(stream) << 32;
  if (o.history_states == 1) h.add_ids(first_id);
  for (uint32_t i = 0; i < o.cells; ++i) {
    if (o.history_states > 1) h.add_ids(first_id + i % o.history_states);
    h.add_times(kT0 + kHistoryInterval * static_cast<double>(i / o.history_states));
    h.add_values(random() % 50 < (i / 97 % 3 == 0 ? 45 : 5) ? 1.0f : 0.0f);
  }
  return request;
}

// Batch k of a stream, either kind.
v1::IngestRequest MakeBatch(const Options& o, int stream, int k, std::mt19937_64& random) {
  return o.history_states > 0 ? MakeHistory(o, stream, random) : MakeScan(o, stream, k, random);
}

// The ceiling of a history: the arithmetic one observation at a time of its own needs at the least,
// one core — the phasors of the default 24 harmonic periods (604800 / k s: one fmod and one sincos,
// then powers of e^{jω_1 t}) and the fold of the value into a state's 96 doubles (S̄ and Ē per
// period), which no batching amortises. Printed as observations per second.
void MeasureHistoryCeiling(const Options& o) {
  constexpr int kPeriods = 24;
  constexpr int kTimes = 2'000'000;
  std::vector<double> body(4 * kPeriods, 0.0);
  const auto start = Clock::now();
  for (int i = 0; i < kTimes; ++i) {
    const double t = kT0 + kHistoryInterval * i;
    const double phase = 2.0 * 3.141592653589793 * (std::fmod(t, 604800.0) / 604800.0);
    const double c1 = std::cos(phase), s1 = -std::sin(phase);
    const double d = 1.0 / (i + 1), s = (i % 3 == 0) ? 1.0 : 0.0;
    double c = c1, sn = s1;
    for (int k = 0; k < kPeriods; ++k) {
      double* b = &body[4 * k];
      b[0] += d * (s * c - b[0]);
      b[1] += d * (s * sn - b[1]);
      b[2] += d * (c - b[2]);
      b[3] += d * (sn - b[3]);
      const double next = c * c1 - sn * s1;
      sn = sn * c1 + c * s1;
      c = next;
    }
  }
  const double elapsed = Seconds(Clock::now() - start);
  double sink = 0;
  for (const double v : body) sink += v;
  std::printf("ceiling: phasors of %d periods at a new time and the fold, one core: %.2fM obs/s (checksum %.6f)\n",
              kPeriods, kTimes / elapsed / 1e6, sink);
  (void)o;
}

// What one scan costs on the wire and to encode and decode, one core.
void MeasureEncoding(const Options& o) {
  std::mt19937_64 random(1);
  v1::IngestRequest scan = MakeBatch(o, 0, 0, random);
  scan.set_writer_id(1);
  scan.set_sequence(12345);
  if (o.history_states == 0) scan.set_time(kT0);
  constexpr int kReps = 200;
  std::string bytes;
  auto start = Clock::now();
  for (int i = 0; i < kReps; ++i) scan.SerializeToString(&bytes);
  const double encode = Seconds(Clock::now() - start) / kReps;
  v1::IngestRequest parsed;
  start = Clock::now();
  for (int i = 0; i < kReps; ++i) parsed.ParseFromString(bytes);
  const double decode = Seconds(Clock::now() - start) / kReps;
  const bool history = o.history_states > 0;
  std::printf("%s: one %s of %u %s: %zu bytes (%.1f per observation); encode %.0f µs, decode %.0f µs "
              "(%.0fM observations/s to decode on one core)\n",
              history ? "history" : o.encoding.c_str(), history ? "history" : "scan", o.cells,
              history ? "observations" : "cells", bytes.size(), static_cast<double>(bytes.size()) / o.cells,
              encode * 1e6, decode * 1e6,
              o.cells / decode / 1e6);
}

// One Ingest stream: up to `window` batches unacknowledged, counting the acknowledgements and their
// latencies.
class LoadStream {
 public:
  LoadStream(const Options& o, const Client& client, int index)
      : o_(o), client_(client), index_(index), writer_id_(std::random_device()() << 16 | index) {}

  void Start() {
    stub_ = v1::IngestService::NewStub(client_.NewChannel());
    std::mt19937_64 random(index_);
    for (int k = 0; k < kScansPerStream; ++k) scans_.push_back(MakeBatch(o_, index_, k, random));
    sent_at_.resize(static_cast<size_t>(o_.window) * 2);
    stream_ = std::make_unique<fremen::bench::WindowedIngest>(
        *stub_, client_.Context(), o_.window, [this](uint64_t sequence) { return Next(sequence); },
        [this](const v1::IngestResponse& ack) { Acknowledged(ack); });
  }
  // Stops writing (with `drain`, only once --batches are written), waits for the outstanding
  // acknowledgements; the call's status.
  grpc::Status Stop(bool drain = false) {
    if (!drain) stream_->Stop();
    return stream_->Await();
  }

  std::atomic<uint64_t> observations{0};
  std::atomic<uint64_t> batches{0};
  std::atomic<bool> failed{false};
  // Write-to-acknowledgement seconds, under mutex_.
  std::vector<double> TakeLatencies() {
    std::lock_guard lock(mutex_);
    return std::exchange(latencies_, {});
  }

 private:
  const v1::IngestRequest* Next(uint64_t sequence) {
    if (o_.batches > 0 && sequence >= o_.batches) return nullptr;
    {
      std::lock_guard lock(mutex_);
      sent_at_[sequence % sent_at_.size()] = Clock::now();
    }
    v1::IngestRequest& scan = scans_[sequence % scans_.size()];
    scan.set_writer_id(writer_id_);
    scan.set_sequence(sequence);
    if (o_.history_states > 0) {
      // Right after the previous batch's times: a log uploaded in order.
      const double span = kHistoryInterval * std::ceil(static_cast<double>(o_.cells) / o_.history_states);
      double& base = history_base_[sequence % scans_.size()];
      const double shift = kT0 + span * static_cast<double>(sequence) - base;
      for (double& t : *scan.mutable_history()->mutable_times()) t += shift;
      base += shift;
    } else {
      scan.set_time(kT0 + kScanInterval * static_cast<double>(sequence));
    }
    return &scan;
  }

  void Acknowledged(const v1::IngestResponse& ack) {
    if (ack.has_error() || ack.rejected() > 0) {
      if (!failed.exchange(true)) {
        std::fprintf(stderr, "stream %d: batch %lu: %s (%lu rejected)\n", index_,
                     static_cast<unsigned long>(ack.sequence()), ack.error().message().c_str(),
                     static_cast<unsigned long>(ack.rejected()));
      }
    }
    observations += ack.accepted();
    ++batches;
    std::lock_guard lock(mutex_);
    latencies_.push_back(Seconds(Clock::now() - sent_at_[ack.sequence() % sent_at_.size()]));
  }

  const Options& o_;
  const Client& client_;
  const int index_;
  const uint64_t writer_id_;
  std::unique_ptr<v1::IngestService::Stub> stub_;
  std::vector<v1::IngestRequest> scans_;  // cycled through; one is being written at a time
  std::vector<double> history_base_ = std::vector<double>(kScansPerStream, kT0);  // each history's first time
  std::mutex mutex_;
  std::vector<Clock::time_point> sent_at_;  // by sequence modulo its size (> window)
  std::vector<double> latencies_;
  // Last: destroyed first, its call ends before what its reactions use goes.
  std::unique_ptr<fremen::bench::WindowedIngest> stream_;
};

// --batches: every stream sends its fixed number of batches; false when a stream failed.
bool RunFixed(const Options& o, const Client& client) {
  std::vector<std::unique_ptr<LoadStream>> streams;
  for (int s = 0; s < o.streams; ++s) streams.push_back(std::make_unique<LoadStream>(o, client, s));
  for (auto& s : streams) s->Start();
  bool ok = true;
  uint64_t observations = 0;
  for (auto& s : streams) {
    const grpc::Status status = s->Stop(/*drain=*/true);
    ok = ok && status.ok() && !s->failed;
    if (!status.ok()) std::fprintf(stderr, "stream ended with %d: %s\n", status.error_code(), status.error_message().c_str());
    observations += s->observations;
  }
  std::printf("fixed: %d streams × %lu batches × %u cells: %lu cell-observations acknowledged\n", o.streams,
              static_cast<unsigned long>(o.batches), o.cells, static_cast<unsigned long>(observations));
  return ok;
}

// Runs the streams and prints the figures; false when a stream failed.
bool RunIngest(const Options& o, const Client& client) {
  std::vector<std::unique_ptr<LoadStream>> streams;
  for (int s = 0; s < o.streams; ++s) streams.push_back(std::make_unique<LoadStream>(o, client, s));
  for (auto& s : streams) s->Start();
  const auto total = [&] {
    uint64_t observations = 0, batches = 0;
    for (auto& s : streams) {
      observations += s->observations;
      batches += s->batches;
    }
    return std::pair(observations, batches);
  };
  const auto failed = [&] {
    return std::any_of(streams.begin(), streams.end(), [](const auto& s) { return s->failed.load(); });
  };
  std::this_thread::sleep_for(std::chrono::duration<double>(o.warmup));
  for (auto& s : streams) s->TakeLatencies();
  std::vector<double> rates, batch_rates, latencies;
  // A scan observes cells, a history states.
  const char* unit = o.history_states > 0 ? "obs/s" : "cell-obs/s";
  for (int r = 0; r < o.repetitions && !failed(); ++r) {
    const auto [obs0, batches0] = total();
    const auto start = Clock::now();
    std::this_thread::sleep_for(std::chrono::duration<double>(o.seconds));
    const auto [obs1, batches1] = total();
    const double elapsed = Seconds(Clock::now() - start);
    rates.push_back(static_cast<double>(obs1 - obs0) / elapsed);
    batch_rates.push_back(static_cast<double>(batches1 - batches0) / elapsed);
    std::printf("  window %d: %.2fM %s, %.0f batches/s\n", r + 1, rates.back() / 1e6, unit, batch_rates.back());
    std::fflush(stdout);
  }
  for (auto& s : streams) {
    std::vector<double> l = s->TakeLatencies();
    latencies.insert(latencies.end(), l.begin(), l.end());
  }
  bool ok = !failed();
  for (auto& s : streams) {
    const grpc::Status status = s->Stop();
    if (!status.ok()) {
      std::fprintf(stderr, "stream ended with %d: %s\n", status.error_code(), status.error_message().c_str());
      ok = false;
    }
  }
  std::sort(latencies.begin(), latencies.end());
  const std::string what = o.history_states > 0
                               ? std::to_string(o.cells) + "-observation histories of " +
                                     std::to_string(o.history_states) + " state(s)"
                               : std::to_string(o.cells) + "-cell scans";
  std::printf("ingest: %d streams × %s, ≤ %d unacknowledged each: median %.2fM %s "
              "(%.0f batches/s) over %zu windows of %.0f s; ack latency p50 %.1f ms, p99 %.1f ms\n",
              o.streams, what.c_str(), o.window, Median(rates) / 1e6, unit, Median(batch_rates), rates.size(), o.seconds,
              Quantile(latencies, 0.5) * 1e3, Quantile(latencies, 0.99) * 1e3);
  return ok;
}

void Client::Predict() const {
  if (o_.predict_calls <= 0) return;
  std::mt19937_64 random(7);
  std::vector<double> latencies;
  latencies.reserve(o_.predict_calls);
  const auto start = Clock::now();
  for (int i = 0; i < o_.predict_calls; ++i) {
    v1::PredictRequest request;
    request.set_map(o_.map);
    v1::CellIndices& cell = *request.mutable_states()->mutable_cells();
    cell.add_x(static_cast<uint32_t>(random() % o_.grid));
    cell.add_y(static_cast<uint32_t>(random() % o_.grid));
    cell.add_z(0);
    request.add_times(kT0 + 3600.0 * static_cast<double>(random() % 168));
    v1::PredictResponse response;
    const auto call_start = Clock::now();
    const grpc::Status status = query_->Predict(Context().get(), request, &response);
    latencies.push_back(Seconds(Clock::now() - call_start));
    if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
      std::printf("predict: skipped, the daemon does not serve QueryService yet\n");
      return;
    }
    if (!status.ok()) {
      std::fprintf(stderr, "Predict: %s\n", status.error_message().c_str());
      return;
    }
  }
  const double elapsed = Seconds(Clock::now() - start);
  std::sort(latencies.begin(), latencies.end());
  std::printf("predict: single state, one call at a time: p50 %.0f µs, p99 %.0f µs, %.0f calls/s\n",
              Quantile(latencies, 0.5) * 1e6, Quantile(latencies, 0.99) * 1e6, o_.predict_calls / elapsed);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app("fremen_ingest_load: ingest throughput of a running fremend (benchmark)");
  app.add_option("--address", o.address, "fremend's HOST:PORT")->capture_default_str();
  app.add_option("--map", o.map, "grid map to ingest into (created when missing)")->capture_default_str();
  app.add_option("--token", o.token, "bearer token with write access, when the daemon wants one");
  app.add_option("--grid", o.grid, "cells along each axis of a created map")->capture_default_str()->check(CLI::Range(1, 2048));
  app.add_option("--streams", o.streams, "concurrent Ingest streams")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--cells", o.cells, "cells per scan")->capture_default_str()->check(CLI::Range(1, 1 << 24));
  app.add_option("--window", o.window, "unacknowledged batches per stream (the clients' default)")->capture_default_str()->check(CLI::Range(1, 1024));
  app.add_option("--warmup", o.warmup, "seconds before measuring")->capture_default_str();
  app.add_option("--seconds", o.seconds, "seconds per measured window")->capture_default_str();
  app.add_option("--repetitions", o.repetitions, "measured windows (the median is reported)")->capture_default_str()->check(CLI::Range(1, 1000));
  app.add_option("--history-states", o.history_states,
                 "stream histories (a time per observation) of this many states per stream into a generic map "
                 "instead of scans (0: scans); --cells is then the observations per batch")
      ->capture_default_str();
  app.add_option("--predict-calls", o.predict_calls, "single-state Predict calls afterwards (0: none)")->capture_default_str();
  app.add_option("--encoding", o.encoding, "cells (CellObservations) or compact (CompactCells)")
      ->capture_default_str()
      ->check(CLI::IsMember({"cells", "compact"}));
  app.add_option("--batches", o.batches, "send exactly this many batches per stream, then stop (a fixed workload; 0: timed windows)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (o.history_states > 0) {
    if (app.count("--map") == 0) o.map = "ingest-load-history";
    o.predict_calls = 0;  // the Predict latency is of grid cells
  } else if (uint64_t{o.grid} * o.grid * o.grid < o.cells) {
    std::fprintf(stderr, "--cells %u exceeds the grid's %u³ cells\n", o.cells, o.grid);
    return 2;
  }

  const Client client(o);
  if (!client.EnsureMap()) return 1;
  if (o.batches > 0) return RunFixed(o, client) ? 0 : 1;
  MeasureEncoding(o);
  if (o.history_states > 0) MeasureHistoryCeiling(o);
  const bool ok = RunIngest(o, client);
  client.Predict();
  return ok ? 0 : 1;
}
