// fremen_query_load: measures QueryService as a C++ client sees it (targets: docs/performance.md,
// "Targets") and prints medians:
//   - PredictRegion of a box (default 1000×1000 = 1M cells) delivered as FLOAT and as UINT8:
//     seconds per box and cells/s (targets ≥ 800M cells/s as UINT8, ≥ 300M as FLOAT), each next to
//     its ceiling of the same run: the same box of a map where nothing was observed (made by
//     --create), i.e. the answer's path without the prediction;
//   - PredictRegionSeries of the same box at --series-times times (default 96: a day every 15
//     minutes) as FLOAT and UINT8: seconds per call, delivered cell-predictions/s (cells × times /
//     seconds) and the values and bytes on the wire, next to two ceilings of the same run: the box
//     asked time by time (cells / PredictRegion's median) and the loopback byte rate of the single-
//     time PredictRegion stream;
//   - single-state Predict: latency p50/p99 with one call in flight (targets p50 ≤ 200 µs,
//     p99 ≤ 1 ms) and the sustained rate, with one and with several calls in flight on one channel,
//     and the rate of predictions when each call asks for many states (the original FremenServer:
//     ~80k predictions/s).
// Against a running fremend. With --create it first creates a grid map (and the ceiling's empty
// one, "<map>-unobserved") and fills it through the IngestService (a dense patch per scan: walls,
// free space and 1/8 of the cells on a daily rhythm), running the update job through the
// AdminService after each simulated day, as the nightly job would, so that dynamic cells hold
// published models whose orders were chosen on evidence.
// Without those services, prepare a map another way (see client/bench/README.md).
//
// Uses only the API (fremen_proto + gRPC), as any client does. Single-threaded except for the
// --concurrency threads of the Predict rate and the ingest acknowledgement reader.
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "client/bench/load_stats.h"
#include "fremen/v1/admin.grpc.pb.h"
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

struct Options {
  std::string address = "127.0.0.1:50051";
  std::string map = "bench";
  std::string token;
  bool create = false;
  uint32_t size = 1000;       // grid (when creating) and box: size × size cells
  uint32_t scans = 56;        // --create: scans of the whole grid
  double scan_interval = 21600;  // seconds between scans (4 a day: 14 days)
  int region_reps = 15;
  int series_times = 96;  // PredictRegionSeries: times a call
  int series_reps = 7;
  int predict_calls = 20000;
  int concurrency = 8;
  int batch = 1000;          // states per call of the batched Predict
  int large_batch = 10000;   // and a larger batch
  int windows = 5;           // windows per batched figure (their median is printed)
  double window_predictions = 2e6;  // predictions per window of the batched Predict
  bool batched_only = false;  // only the batched Predict and its ceilings (for profiling the daemon)
  std::string region_outputs = "both";  // float, uint8 or both (one alone: for profiling the daemon)
};

const char kUsage[] =
    "usage: fremen_query_load [--address=HOST:PORT] [--map=NAME] [--token=TOKEN] [--create]\n"
    "                         [--size=CELLS] [--scans=N] [--scan-interval=S] [--region-reps=N]\n"
    "                         [--series-times=N] [--series-reps=N] [--predict-calls=N]\n"
    "                         [--concurrency=N] [--batch=STATES] [--large-batch=STATES]\n"
    "                         [--windows=N] [--window-predictions=N] [--batched-only]\n"
    "                         [--region-outputs=float|uint8|both]\n";

Options Parse(int argc, char** argv) {
  Options o;
  std::map<std::string, std::string> flags;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) {
      std::fputs(kUsage, stderr);
      std::exit(2);
    }
    const size_t eq = arg.find('=');
    flags[arg.substr(2, eq == std::string::npos ? std::string::npos : eq - 2)] =
        eq == std::string::npos ? "" : arg.substr(eq + 1);
  }
  for (const auto& [key, value] : flags) {
    if (key == "address") o.address = value;
    else if (key == "map") o.map = value;
    else if (key == "token") o.token = value;
    else if (key == "create") o.create = true;
    else if (key == "size") o.size = static_cast<uint32_t>(std::stoul(value));
    else if (key == "scans") o.scans = static_cast<uint32_t>(std::stoul(value));
    else if (key == "scan-interval") o.scan_interval = std::stod(value);
    else if (key == "region-reps") o.region_reps = std::max(0, std::stoi(value));
    else if (key == "series-times") o.series_times = std::max(1, std::stoi(value));
    else if (key == "series-reps") o.series_reps = std::max(0, std::stoi(value));
    else if (key == "predict-calls") o.predict_calls = std::max(0, std::stoi(value));
    else if (key == "concurrency") o.concurrency = std::stoi(value);
    else if (key == "batch") o.batch = std::stoi(value);
    else if (key == "large-batch") o.large_batch = std::stoi(value);
    else if (key == "batched-only") o.batched_only = true;
    else if (key == "region-outputs") {
      if (value != "float" && value != "uint8" && value != "both") {
        std::fprintf(stderr, "--region-outputs must be float, uint8 or both, got \"%s\"\n", value.c_str());
        std::exit(2);
      }
      o.region_outputs = value;
    }
    else if (key == "windows") o.windows = std::max(1, std::stoi(value));
    else if (key == "window-predictions") o.window_predictions = std::stod(value);
    else {
      std::fprintf(stderr, "unknown flag --%s\n%s", key.c_str(), kUsage);
      std::exit(2);
    }
  }
  return o;
}

class Bench {
 public:
  explicit Bench(const Options& o)
      : o_(o),
        channel_(grpc::CreateCustomChannel(o.address, grpc::InsecureChannelCredentials(), ChannelArgs())),
        maps_(v1::MapService::NewStub(channel_)),
        ingest_(v1::IngestService::NewStub(channel_)),
        admin_(v1::AdminService::NewStub(channel_)),
        query_(v1::QueryService::NewStub(channel_)) {}

  // A context naming the map (for proxies; o_.map unless another is named) and carrying the token.
  void Prepare(grpc::ClientContext& context, const std::string& map = "") const {
    context.AddMetadata("x-fremen-map", map.empty() ? o_.map : map);
    if (!o_.token.empty()) context.AddMetadata("authorization", "Bearer " + o_.token);
  }

  bool CreateAndFill();
  // The median seconds of a box and its wire bytes (0 on failure).
  struct RegionRun {
    double seconds = 0;
    uint64_t wire_bytes = 0;
  };
  // `map`: o_.map, or the ceiling map (CeilingMap()) for the ceiling of the same box.
  RegionRun Region(v1::RegionOutput output, const char* name, const std::string& map);
  // The regions' ceiling: the same box of a grid of the same size where nothing was observed, so
  // that the daemon predicts nothing (every cell is 0.5) and what is left is the path of the answer
  // — the block's fill, its encoding, serialisation, the loopback, the client's parse. Made by
  // --create beside the filled map.
  std::string CeilingMap() const { return o_.map + "-unobserved"; }
  bool CreateGrid(const std::string& name);
  // The ceiling's figures beside `run` (the filled map's), when the ceiling map exists.
  void RegionCeiling(v1::RegionOutput output, const char* name, const RegionRun& run);
  // `single`: the same box's PredictRegion, for the ceilings.
  void RegionSeries(v1::RegionOutput output, const char* name, const RegionRun& single);
  void Predict();
  // The rate of predictions when calls ask for many states: `windows` windows each of --batch and
  // --large-batch states a call, with 1 and with --concurrency calls in flight, beside two ceilings
  // of the same run.
  void BatchedPredict();

 private:
  struct BatchFigures {
    double rate = 0;     // median over the windows: states (predictions) per second
    double latency = 0;  // median seconds a call
  };
  // `states` states a call (random cells, the requests made before the clock starts), `concurrency`
  // threads calling on the one channel, `calls` calls each a window; false on an error.
  bool Batched(int states, int concurrency, int calls, BatchFigures& figures);
  std::vector<v1::PredictRequest> MakeRequests(int count, int states, uint64_t seed) const;

  static grpc::ChannelArguments ChannelArgs() {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(64 << 20);
    args.SetMaxSendMessageSize(64 << 20);
    return args;
  }
  // Scans [first, first + count) through one Ingest stream.
  bool Fill(uint32_t first, uint32_t count);
  bool Update();
  // Latencies (seconds) of `calls` Predicts of `states` random cells each, one at a time; `seed`
  // picks the cells.
  std::vector<double> PredictLoop(int calls, int states, uint64_t seed, bool* ok);

  const Options o_;
  // Ours for this run: a rerun does not look like a retry of an earlier run's scans.
  const uint64_t writer_ = std::random_device()();
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::IngestService::Stub> ingest_;
  std::unique_ptr<v1::AdminService::Stub> admin_;
  std::unique_ptr<v1::QueryService::Stub> query_;
};

bool Bench::CreateGrid(const std::string& name) {
  grpc::ClientContext context;
  Prepare(context, name);
  v1::CreateMapRequest request;
  v1::Map& map = *request.mutable_map();
  map.set_name(name);
  map.set_kind(v1::MAP_KIND_GRID);
  map.mutable_grid()->set_resolution(0.05);
  map.mutable_grid()->mutable_size()->set_x(o_.size);
  map.mutable_grid()->mutable_size()->set_y(o_.size);
  v1::CreateMapResponse response;
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  if (!status.ok()) {
    std::fprintf(stderr, "CreateMap %s: %s\n", name.c_str(), status.error_message().c_str());
    return false;
  }
  return true;
}

bool Bench::CreateAndFill() {
  if (!CreateGrid(o_.map) || !CreateGrid(CeilingMap())) return false;
  const uint32_t per_day = std::max(1u, static_cast<uint32_t>(std::lround(86400 / o_.scan_interval)));
  const auto start = Clock::now();
  for (uint32_t first = 0; first < o_.scans; first += per_day) {
    if (!Fill(first, std::min(per_day, o_.scans - first)) || !Update()) return false;
  }
  const double secs = Seconds(Clock::now() - start);
  const double cells = static_cast<double>(o_.size) * o_.size;
  std::printf("filled %s: %u scans of %.0f cells, updated daily, in %.2f s (%.1fM cell-obs/s with the updates)\n",
              o_.map.c_str(), o_.scans, cells, secs, o_.scans * cells / secs / 1e6);
  return true;
}

bool Bench::Fill(uint32_t first, uint32_t count) {
  const uint64_t cells = uint64_t{o_.size} * o_.size;
  // Two patches: day and night. Walls (every 16th row) always occupied, 1/8 of the columns occupied
  // by day (doors, people), the rest free.
  std::string day(cells, '\0'), night(cells, '\0');
  for (uint64_t i = 0; i < cells; ++i) {
    const uint64_t x = i % o_.size, y = i / o_.size;
    if (y % 16 == 0) day[i] = night[i] = static_cast<char>(255);
    else if (x % 8 == 0) day[i] = static_cast<char>(255);
  }
  grpc::ClientContext context;
  Prepare(context);
  auto stream = ingest_->Ingest(&context);
  std::atomic<uint64_t> acked{0}, refused{0};
  std::thread reader([&] {
    v1::IngestResponse ack;
    while (stream->Read(&ack)) {
      if (ack.error().code() != 0) ++refused;
      ++acked;
    }
  });
  for (uint32_t s = first; s < first + count; ++s) {
    v1::IngestRequest batch;
    batch.set_map(o_.map);
    batch.set_writer_id(writer_);
    batch.set_sequence(s + 1);
    batch.set_time(kT0 + o_.scan_interval * s);
    const double hour = std::fmod(batch.time(), 86400.0) / 3600.0;
    v1::DensePatch& patch = *batch.mutable_patch();
    patch.mutable_size()->set_x(o_.size);
    patch.mutable_size()->set_y(o_.size);
    patch.mutable_size()->set_z(1);
    patch.set_probabilities(hour >= 8 && hour < 20 ? day : night);
    if (!stream->Write(batch)) break;
  }
  stream->WritesDone();
  reader.join();
  const grpc::Status status = stream->Finish();
  if (!status.ok() || acked != count || refused != 0) {
    std::fprintf(stderr,
                 "Ingest: %s (%llu of %u scans acknowledged, %llu refused). Without the IngestService, "
                 "prepare the map as client/bench/README.md says.\n",
                 status.error_message().c_str(), static_cast<unsigned long long>(acked.load()), count,
                 static_cast<unsigned long long>(refused.load()));
    return false;
  }
  return true;
}

bool Bench::Update() {
  grpc::ClientContext context;
  Prepare(context);
  v1::RunUpdateRequest request;
  request.set_map(o_.map);
  v1::Operation operation;
  grpc::Status status = admin_->RunUpdate(&context, request, &operation);
  while (status.ok() && !operation.done()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    grpc::ClientContext poll;
    Prepare(poll);
    v1::GetOperationRequest get;
    get.set_map(o_.map);
    get.set_name(operation.name());
    status = admin_->GetOperation(&poll, get, &operation);
  }
  if (!status.ok() || operation.error().code() != 0) {
    std::fprintf(stderr, "RunUpdate: %s%s (predictions will use γ0 only)\n", status.error_message().c_str(),
                 operation.error().message().c_str());
    return false;
  }
  return true;
}

Bench::RegionRun Bench::Region(v1::RegionOutput output, const char* name, const std::string& map) {
  v1::PredictRegionRequest request;
  request.set_map(map);
  request.mutable_hi()->set_x(o_.size);
  request.mutable_hi()->set_y(o_.size);
  request.set_time(kT0 + o_.scan_interval * o_.scans + 3600);
  request.set_output(output);
  const uint64_t cells = uint64_t{o_.size} * o_.size;
  std::vector<double> seconds;
  uint64_t wire_bytes = 0;
  for (int rep = 0; rep < o_.region_reps; ++rep) {
    grpc::ClientContext context;
    Prepare(context, map);
    const auto start = Clock::now();
    auto reader = query_->PredictRegion(&context, request);
    v1::PredictRegionResponse chunk;
    uint64_t received = 0, chunks = 0;
    wire_bytes = 0;
    while (reader->Read(&chunk)) {
      received += chunk.float_values_size() + chunk.bytes_values().size();
      wire_bytes += chunk.ByteSizeLong();
      ++chunks;
    }
    const grpc::Status status = reader->Finish();
    if (!status.ok() || received != cells) {
      std::fprintf(stderr, "PredictRegion %s of %s: %s (%llu of %llu cells)\n", name, map.c_str(),
                   status.error_message().c_str(), static_cast<unsigned long long>(received),
                   static_cast<unsigned long long>(cells));
      return {};
    }
    seconds.push_back(Seconds(Clock::now() - start));
    if (rep == 0 && map == o_.map) {
      std::printf("PredictRegion %-5s %llu cells in %llu chunks\n", name, static_cast<unsigned long long>(cells),
                  static_cast<unsigned long long>(chunks));
    }
  }
  const double median = Median(seconds);
  std::printf("%sPredictRegion %-5s median %.2f ms per box = %.1fM cells/s (best %.2f ms), %.0f MB/s on the wire\n",
              map == o_.map ? "" : "  ceiling, the same box with nothing observed: ", name, median * 1e3,
              static_cast<double>(cells) / median / 1e6, *std::min_element(seconds.begin(), seconds.end()) * 1e3,
              wire_bytes / median / 1e6);
  return {median, wire_bytes};
}

void Bench::RegionCeiling(v1::RegionOutput output, const char* name, const RegionRun& run) {
  if (run.seconds == 0) return;
  grpc::ClientContext context;
  Prepare(context, CeilingMap());
  v1::GetMapRequest request;
  request.set_map(CeilingMap());
  v1::GetMapResponse map;
  if (!maps_->GetMap(&context, request, &map).ok()) {
    std::printf("  (no ceiling: map %s is missing; --create makes it)\n", CeilingMap().c_str());
    return;
  }
  const RegionRun ceiling = Region(output, name, CeilingMap());
  if (ceiling.seconds > 0) {
    std::printf("  the filled map's box at %.0f%% of the ceiling's rate\n", 100 * ceiling.seconds / run.seconds);
  }
}

void Bench::RegionSeries(v1::RegionOutput output, const char* name, const RegionRun& single) {
  v1::PredictRegionSeriesRequest request;
  request.set_map(o_.map);
  request.mutable_hi()->set_x(o_.size);
  request.mutable_hi()->set_y(o_.size);
  // A day after the scans, evenly spaced (96: every 15 minutes).
  const double day_start = kT0 + o_.scan_interval * o_.scans;
  for (int i = 0; i < o_.series_times; ++i) request.add_times(day_start + 86400.0 * i / o_.series_times);
  request.set_output(output);
  const uint64_t cells = uint64_t{o_.size} * o_.size;
  std::vector<double> seconds;
  uint64_t values = 0, wire_bytes = 0, varying = 0;
  for (int rep = 0; rep < o_.series_reps; ++rep) {
    grpc::ClientContext context;
    Prepare(context);
    const auto start = Clock::now();
    auto reader = query_->PredictRegionSeries(&context, request);
    v1::PredictRegionSeriesResponse chunk;
    values = wire_bytes = 0;
    while (reader->Read(&chunk)) {
      values += chunk.float_values_size() + chunk.bytes_values().size();
      wire_bytes += chunk.ByteSizeLong();
      varying = chunk.varying_cells();
    }
    const grpc::Status status = reader->Finish();
    const uint64_t expected = cells - varying + varying * static_cast<uint64_t>(o_.series_times);
    if (!status.ok() || values != expected) {
      std::fprintf(stderr, "PredictRegionSeries %s: %s (%llu of %llu values)\n", name,
                   status.error_message().c_str(), static_cast<unsigned long long>(values),
                   static_cast<unsigned long long>(expected));
      return;
    }
    seconds.push_back(Seconds(Clock::now() - start));
  }
  const double median = Median(seconds);
  const double delivered = static_cast<double>(cells) * o_.series_times;
  std::printf("PredictRegionSeries %-5s %d times, %llu of %llu cells varying: %.1fM values, %.1f MB on the wire\n",
              name, o_.series_times, static_cast<unsigned long long>(varying), static_cast<unsigned long long>(cells),
              values / 1e6, wire_bytes / 1e6);
  std::printf("PredictRegionSeries %-5s median %.2f ms per call = %.0fM cell-predictions/s delivered (best %.2f ms), "
              "%.0f MB/s on the wire\n",
              name, median * 1e3, delivered / median / 1e6, *std::min_element(seconds.begin(), seconds.end()) * 1e3,
              wire_bytes / median / 1e6);
  if (single.seconds > 0) {
    std::printf("  ceilings of this run: the box time by time %.0fM cell-predictions/s (the series delivers %.1fx that); "
                "PredictRegion's wire rate %.0f MB/s\n",
                cells / single.seconds / 1e6, delivered / median / (cells / single.seconds),
                single.wire_bytes / single.seconds / 1e6);
  }
}

std::vector<double> Bench::PredictLoop(int calls, int states, uint64_t seed, bool* ok) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<uint32_t> cell(0, o_.size - 1);
  v1::PredictRequest request;
  request.set_map(o_.map);
  request.add_times(kT0 + o_.scan_interval * o_.scans + 3600);
  v1::CellIndices& cells = *request.mutable_states()->mutable_cells();
  cells.mutable_x()->Resize(states, 0);
  cells.mutable_y()->Resize(states, 0);
  std::vector<double> latencies;
  latencies.reserve(calls);
  for (int i = 0; i < calls; ++i) {
    for (int j = 0; j < states; ++j) {
      cells.set_x(j, cell(rng));
      cells.set_y(j, cell(rng));
    }
    grpc::ClientContext context;
    Prepare(context);
    v1::PredictResponse response;
    const auto start = Clock::now();
    const grpc::Status status = query_->Predict(&context, request, &response);
    latencies.push_back(Seconds(Clock::now() - start));
    if (!status.ok() || response.probabilities_size() != states) {
      std::fprintf(stderr, "Predict: %s\n", status.error_message().c_str());
      *ok = false;
      break;
    }
  }
  return latencies;
}

std::vector<v1::PredictRequest> Bench::MakeRequests(int count, int states, uint64_t seed) const {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<uint32_t> cell(0, o_.size - 1);
  std::vector<v1::PredictRequest> requests(count);
  for (v1::PredictRequest& request : requests) {
    request.set_map(o_.map);
    request.add_times(kT0 + o_.scan_interval * o_.scans + 3600);
    v1::CellIndices& cells = *request.mutable_states()->mutable_cells();
    for (int j = 0; j < states; ++j) {
      cells.add_x(cell(rng));
      cells.add_y(cell(rng));
    }
  }
  return requests;
}

bool Bench::Batched(int states, int concurrency, int calls, BatchFigures& figures) {
  // A few distinct requests a thread, so that no cache holds one call's states for the next.
  constexpr int kRequestsPerThread = 4;
  std::vector<std::vector<v1::PredictRequest>> requests(concurrency);
  for (int t = 0; t < concurrency; ++t) requests[t] = MakeRequests(kRequestsPerThread, states, 1000 + t);
  std::atomic<bool> ok{true};
  std::vector<double> rates, latencies;
  for (int window = 0; window <= o_.windows; ++window) {  // window 0 warms up
    std::vector<std::vector<double>> per_thread(concurrency);
    std::vector<std::thread> threads;
    const auto start = Clock::now();
    for (int t = 0; t < concurrency; ++t) {
      threads.emplace_back([&, t] {
        v1::PredictResponse response;
        for (int i = 0; i < calls && ok; ++i) {
          grpc::ClientContext context;
          Prepare(context);
          response.Clear();
          const auto call_start = Clock::now();
          const grpc::Status status = query_->Predict(&context, requests[t][i % kRequestsPerThread], &response);
          per_thread[t].push_back(Seconds(Clock::now() - call_start));
          if (!status.ok() || response.probabilities_size() != states) {
            std::fprintf(stderr, "Predict: %s\n", status.error_message().c_str());
            ok = false;
          }
        }
      });
    }
    for (std::thread& thread : threads) thread.join();
    const double elapsed = Seconds(Clock::now() - start);
    if (!ok) return false;
    if (window == 0) continue;
    rates.push_back(static_cast<double>(states) * calls * concurrency / elapsed);
    for (const auto& v : per_thread) latencies.insert(latencies.end(), v.begin(), v.end());
  }
  figures.rate = Median(rates);
  figures.latency = Median(latencies);
  return true;
}

// The client's own share of a batched call on one core: encoding the request and decoding a
// response of `states` probabilities (what gRPC's codec does for it). The client and the daemon
// share the machine, so this bounds what is left for the daemon.
double ClientCodecRate(const v1::PredictRequest& request) {
  v1::PredictResponse response;
  const int states = request.states().cells().x_size();
  for (int j = 0; j < states; ++j) response.add_probabilities(static_cast<float>(j) / static_cast<float>(states));
  response.set_state_count(static_cast<uint32_t>(states));
  response.set_time_count(1);
  const std::string response_bytes = response.SerializeAsString();
  std::string request_bytes;
  v1::PredictResponse parsed;
  std::vector<double> rates;
  const int reps = std::max(1, 2'000'000 / std::max(states, 1));
  for (int window = 0; window < 5; ++window) {
    const auto start = Clock::now();
    for (int i = 0; i < reps; ++i) {
      request_bytes.clear();
      request.SerializeToString(&request_bytes);
      parsed.ParseFromString(response_bytes);
    }
    rates.push_back(static_cast<double>(states) * reps / Seconds(Clock::now() - start));
  }
  return Median(rates);
}

void Bench::BatchedPredict() {
  const int concurrencies[2] = {1, std::max(1, o_.concurrency)};
  for (const int states : {o_.batch, o_.large_batch}) {
    for (const int concurrency : concurrencies) {
      BatchFigures f;
      const double calls = o_.window_predictions / (static_cast<double>(states) * concurrency);
      if (!Batched(states, concurrency, std::max(1, static_cast<int>(calls)), f)) return;
      std::printf("Predict %d states a call, %d in flight: median of %d windows %.2fM predictions/s, p50 %.0f µs a call\n",
                  states, concurrency, o_.windows, f.rate / 1e6, f.latency * 1e6);
    }
  }
  // Ceilings of the same run: the calls a second when a call asks for one state (what the call
  // itself costs, gRPC and the daemon's per-call work), and the client's codec.
  for (const int concurrency : concurrencies) {
    BatchFigures f;
    if (!Batched(1, concurrency, std::max(1, o_.predict_calls / o_.windows / concurrency), f)) return;
    std::printf("ceiling: 1-state Predict calls, %d in flight: %.0f calls/s = %.1fM / %.1fM predictions/s at %d / %d "
                "states a call\n",
                concurrency, f.rate, f.rate * o_.batch / 1e6, f.rate * o_.large_batch / 1e6, o_.batch, o_.large_batch);
  }
  for (const int states : {o_.batch, o_.large_batch}) {
    std::printf("ceiling: client encode + decode of %d states a call, one core: %.1fM predictions/s\n", states,
                ClientCodecRate(MakeRequests(1, states, 7)[0]) / 1e6);
  }
}

void Bench::Predict() {
  bool ok = true;
  PredictLoop(std::max(1, o_.predict_calls / 10), 1, 1, &ok);  // warm up the connection and caches
  if (!ok) return;
  const auto start = Clock::now();
  std::vector<double> latencies = PredictLoop(o_.predict_calls, 1, 2, &ok);
  const double elapsed = Seconds(Clock::now() - start);
  if (!ok) return;
  std::sort(latencies.begin(), latencies.end());
  std::printf("Predict 1 state, 1 in flight:  p50 %.0f µs, p99 %.0f µs, %.0f predictions/s\n",
              Quantile(latencies, 0.5) * 1e6, Quantile(latencies, 0.99) * 1e6, latencies.size() / elapsed);

  std::vector<std::vector<double>> per_thread(o_.concurrency);
  std::vector<std::thread> threads;
  std::atomic<bool> all_ok{true};
  const int each = std::max(1, o_.predict_calls / o_.concurrency);
  const auto concurrent_start = Clock::now();
  for (int t = 0; t < o_.concurrency; ++t) {
    threads.emplace_back([&, t] {
      bool thread_ok = true;
      per_thread[t] = PredictLoop(each, 1, 100 + t, &thread_ok);
      if (!thread_ok) all_ok = false;
    });
  }
  for (std::thread& thread : threads) thread.join();
  const double concurrent_elapsed = Seconds(Clock::now() - concurrent_start);
  if (!all_ok) return;
  std::vector<double> all;
  for (const auto& v : per_thread) all.insert(all.end(), v.begin(), v.end());
  std::sort(all.begin(), all.end());
  std::printf("Predict 1 state, %d in flight: p50 %.0f µs, p99 %.0f µs, %.0f predictions/s\n", o_.concurrency,
              Quantile(all, 0.5) * 1e6, Quantile(all, 0.99) * 1e6, all.size() / concurrent_elapsed);

}

}  // namespace

int main(int argc, char** argv) {
  const Options options = Parse(argc, argv);
  Bench bench(options);
  if (options.create && !bench.CreateAndFill()) return 1;
  // A count of 0 leaves its part out (e.g. --series-reps=0 --predict-calls=0: regions only, for
  // profiling the daemon); the series' ceilings need the regions.
  if (!options.batched_only && options.region_reps > 0) {
    const bool floats_too = options.region_outputs != "uint8", bytes_too = options.region_outputs != "float";
    Bench::RegionRun floats, bytes;
    if (floats_too) {
      floats = bench.Region(v1::REGION_OUTPUT_FLOAT, "FLOAT", options.map);
      bench.RegionCeiling(v1::REGION_OUTPUT_FLOAT, "FLOAT", floats);
    }
    if (bytes_too) {
      bytes = bench.Region(v1::REGION_OUTPUT_UINT8, "UINT8", options.map);
      bench.RegionCeiling(v1::REGION_OUTPUT_UINT8, "UINT8", bytes);
    }
    if (options.series_reps > 0) {
      if (floats_too) bench.RegionSeries(v1::REGION_OUTPUT_FLOAT, "FLOAT", floats);
      if (bytes_too) bench.RegionSeries(v1::REGION_OUTPUT_UINT8, "UINT8", bytes);
    }
  }
  // The batched figures' ceilings are made of single-state calls.
  if (options.predict_calls > 0) {
    if (!options.batched_only) bench.Predict();
    bench.BatchedPredict();
  }
  return 0;
}
