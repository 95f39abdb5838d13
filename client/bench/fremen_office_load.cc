// fremen_office_load: the paper's office, streamed (README.md, "Benchmarks"). An office floor of
// about 213,000 cells (client/bench/office_floor.h: rooms, doors, desks, a corridor, cupboards;
// about 4 % of it dynamic) is scanned whole every 5 s of simulated time, and every scan goes to a
// running fremend as CompactCells through gRPC, acknowledged only once durable. --streams robots
// share the floor, each scanning a contiguous band of it (its own writer, its own HTTP/2
// connection, at most --window unacknowledged batches).
//
// It streams --days of simulated time (default a week: 120,960 scans) as fast as the daemon takes
// them and prints the rate of each --seconds window, then the whole run: wall time, the median
// window, the mean, and what the paper's 16 weeks would take at that rate. Printed first, as the
// ceilings of the same run on this machine: how fast one core makes the scans (the client's own
// share) and one core's memory read-modify-write rate.
//
// The map (default "office-load", 584×365×1 cells of 5 cm) is created when missing. Each run
// writes as new writers, from the same simulated start: use a fresh map (or --map) to keep a run's
// model to itself.
//
// Uses only the API (fremen_proto + gRPC), as any client does, on gRPC's callback API
// (client/bench/windowed_ingest.h).
#include <grpcpp/grpcpp.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "CLI/CLI.hpp"
#include "base/compact_scan.h"
#include "client/bench/load_stats.h"
#include "client/bench/office_floor.h"
#include "client/bench/windowed_ingest.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"

namespace {

namespace v1 = fremen::v1;
using fremen::bench::Clock;
using fremen::bench::Median;
using fremen::bench::OfficeFloor;
using fremen::bench::Seconds;

constexpr double kStart = 1700438400;  // Monday 20 November 2023, 00:00 UTC
constexpr double kScanInterval = 5;    // seconds between whole scans of the floor, as in the paper
constexpr double kPaperWeeks = 16;

struct Options {
  std::string address = "127.0.0.1:50051";
  std::string map = "office-load";
  std::string token;
  int streams = 4;
  int window = 64;  // unacknowledged scans per robot: the C++ and Python clients' default
  double days = 7;
  double seconds = 10;  // per printed window
  bool ceilings = true;
};

std::unique_ptr<grpc::ClientContext> Context(const Options& o) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->AddMetadata("x-fremen-map", o.map);
  if (!o.token.empty()) context->AddMetadata("authorization", "Bearer " + o.token);
  return context;
}

// A new channel per robot: one HTTP/2 connection each.
std::shared_ptr<grpc::Channel> NewChannel(const Options& o) {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  args.SetMaxSendMessageSize(-1);
  return grpc::CreateCustomChannel(o.address, grpc::InsecureChannelCredentials(), args);
}

// Creates the office's grid map, or checks that the existing one is the office's size.
bool EnsureMap(const Options& o) {
  auto maps = v1::MapService::NewStub(NewChannel(o));
  v1::GetMapRequest get;
  get.set_map(o.map);
  v1::GetMapResponse got;
  grpc::Status status = maps->GetMap(Context(o).get(), get, &got);
  if (status.ok()) {
    const v1::GridSize& size = got.map().grid().size();
    if (got.map().kind() != v1::MAP_KIND_GRID || size.x() != OfficeFloor::kWidth || size.y() != OfficeFloor::kHeight ||
        size.z() != 1) {
      std::fprintf(stderr, "map %s is not a %u×%u×1 grid; choose another --map\n", o.map.c_str(), OfficeFloor::kWidth,
                   OfficeFloor::kHeight);
      return false;
    }
    std::printf("map %s: %u×%u×1 cells, %u shards\n", o.map.c_str(), OfficeFloor::kWidth, OfficeFloor::kHeight,
                got.map().shards());
    return true;
  }
  if (status.error_code() != grpc::StatusCode::NOT_FOUND) {
    std::fprintf(stderr, "GetMap %s: %s\n", o.map.c_str(), status.error_message().c_str());
    return false;
  }
  v1::CreateMapRequest create;
  v1::Map& map = *create.mutable_map();
  map.set_name(o.map);
  map.set_kind(v1::MAP_KIND_GRID);
  map.mutable_grid()->set_resolution(OfficeFloor::kResolution);
  map.mutable_grid()->mutable_size()->set_x(OfficeFloor::kWidth);
  map.mutable_grid()->mutable_size()->set_y(OfficeFloor::kHeight);
  map.mutable_grid()->mutable_size()->set_z(1);
  v1::CreateMapResponse created;
  status = maps->CreateMap(Context(o).get(), create, &created);
  if (!status.ok()) {
    std::fprintf(stderr, "CreateMap %s: %s\n", o.map.c_str(), status.error_message().c_str());
    return false;
  }
  std::printf("created map %s: %u×%u×1 cells, %u shards\n", o.map.c_str(), OfficeFloor::kWidth, OfficeFloor::kHeight,
              created.map().shards());
  return true;
}

// One robot: scans its band [first, first + count) of the floor at every scan time, keeping up to
// --window scans unacknowledged.
class Robot {
 public:
  Robot(const Options& o, const OfficeFloor& floor, uint64_t scans, uint64_t first, uint64_t count)
      : o_(o), floor_(floor), scans_(scans), first_(first), count_(count), writer_id_(std::random_device()() | 1ull << 40) {}

  void Start() {
    scan_.set_map(o_.map);
    scan_.set_writer_id(writer_id_);
    std::vector<uint64_t> indices(count_);
    for (uint64_t i = 0; i < count_; ++i) indices[i] = first_ + i;
    scan_.mutable_compact()->set_indices(fremen::EncodeIndexGaps(indices));  // the same band every time
    stub_ = v1::IngestService::NewStub(NewChannel(o_));
    stream_ = std::make_unique<fremen::bench::WindowedIngest>(
        *stub_, Context(o_), o_.window, [this](uint64_t k) { return Next(k); },
        [this](const v1::IngestResponse& ack) { Acknowledged(ack); });
  }
  // Waits for every scan's acknowledgement; the call's status.
  grpc::Status Finish() {
    const grpc::Status status = stream_->Await();
    failed = failed || observations < scans_ * count_;
    return status;
  }

  // Whether the stream ended before every scan was acknowledged (the daemon ended it).
  bool EndedShort() const { return stream_->Ended() && observations < scans_ * count_; }

  std::atomic<uint64_t> observations{0};
  std::atomic<bool> failed{false};
  std::atomic<uint64_t> wire_bytes{0};  // of the last scan sent

 private:
  // The scan at time k: the same band, this time's occupied bits.
  const v1::IngestRequest* Next(uint64_t k) {
    if (k >= scans_ || failed) return nullptr;
    const double time = kStart + kScanInterval * static_cast<double>(k);
    scan_.set_sequence(k);
    scan_.set_time(time);
    scan_.mutable_compact()->set_occupied(floor_.Occupied(first_, count_, time));
    wire_bytes = scan_.ByteSizeLong();
    return &scan_;
  }

  void Acknowledged(const v1::IngestResponse& ack) {
    if ((ack.has_error() || ack.rejected() > 0) && !failed.exchange(true)) {
      std::fprintf(stderr, "robot %lu: scan %lu: %s (%lu rejected)\n", static_cast<unsigned long>(first_),
                   static_cast<unsigned long>(ack.sequence()), ack.error().message().c_str(),
                   static_cast<unsigned long>(ack.rejected()));
    }
    observations += ack.accepted();
  }

  const Options& o_;
  const OfficeFloor& floor_;
  const uint64_t scans_, first_, count_, writer_id_;
  std::unique_ptr<v1::IngestService::Stub> stub_;
  v1::IngestRequest scan_;  // being written until the next one is made
  // Last: destroyed first, its call ends before what its reactions use goes.
  std::unique_ptr<fremen::bench::WindowedIngest> stream_;
};

// How fast one core makes whole-floor scans (the occupied bits; the indices are made once), in
// cell-observations per second.
double ScanCeiling(const OfficeFloor& floor) {
  constexpr int kScans = 200;
  size_t sink = 0;
  const auto start = Clock::now();
  for (int k = 0; k < kScans; ++k) sink += floor.Occupied(0, OfficeFloor::kCells, kStart + 36000 + kScanInterval * k).size();
  const double elapsed = Seconds(Clock::now() - start);
  return sink > 0 ? kScans * static_cast<double>(OfficeFloor::kCells) / elapsed : 0;
}

// Prints one core's read-modify-write rate over 256 MiB of floats (median of 5 passes).
void PrintMemoryCeiling() {
  std::vector<float> a(64u << 20, 1.0f);
  std::vector<double> rates;
  for (int pass = 0; pass < 5; ++pass) {
    const auto start = Clock::now();
    for (float& x : a) x = x * 0.999f + 0.5f;
    rates.push_back(2.0 * sizeof(float) * static_cast<double>(a.size()) / Seconds(Clock::now() - start));
  }
  std::printf("ceiling: memory read-modify-write, one core: %.1f GB/s (checksum %.1f)\n", Median(rates) / 1e9,
              static_cast<double>(a[a.size() / 2]));
}

bool Run(const Options& o, const OfficeFloor& floor) {
  const auto scans = static_cast<uint64_t>(std::llround(o.days * 86400 / kScanInterval));
  std::vector<std::unique_ptr<Robot>> robots;
  const uint64_t band = OfficeFloor::kCells / static_cast<uint64_t>(o.streams);
  for (int r = 0; r < o.streams; ++r) {
    const uint64_t first = band * static_cast<uint64_t>(r);
    const uint64_t count = r + 1 == o.streams ? OfficeFloor::kCells - first : band;
    robots.push_back(std::make_unique<Robot>(o, floor, scans, first, count));
  }
  const auto total = [&] {
    uint64_t n = 0;
    for (auto& r : robots) n += r->observations;
    return n;
  };
  const uint64_t expected = scans * OfficeFloor::kCells;
  const auto start = Clock::now();
  for (auto& r : robots) r->Start();
  std::vector<double> rates;
  uint64_t before = 0;
  auto window_start = start;
  while (true) {
    // Sleeps a window, or less once the run is nearly done.
    const uint64_t now_total = total();
    bool any_failed = false;
    for (auto& r : robots) any_failed = any_failed || r->failed || r->EndedShort();
    if (now_total >= expected || any_failed) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const auto now = Clock::now();
    if (Seconds(now - window_start) < o.seconds) continue;
    const uint64_t after = total();
    rates.push_back(static_cast<double>(after - before) / Seconds(now - window_start));
    std::printf("  window %zu: %.2fM cell-obs/s, simulated %.2f of %.2f days\n", rates.size(), rates.back() / 1e6,
                static_cast<double>(after) / OfficeFloor::kCells * kScanInterval / 86400, o.days);
    std::fflush(stdout);
    before = after;
    window_start = now;
  }
  bool ok = true;
  uint64_t wire = 0;
  for (auto& r : robots) {
    const grpc::Status status = r->Finish();
    if (!status.ok()) std::fprintf(stderr, "stream ended with %d: %s\n", status.error_code(), status.error_message().c_str());
    ok = ok && status.ok() && !r->failed;
    wire += r->wire_bytes;
  }
  const double elapsed = Seconds(Clock::now() - start);
  const uint64_t observations = total();
  const double mean = static_cast<double>(observations) / elapsed;
  const double median = rates.empty() ? mean : Median(rates);
  const double paper_seconds = kPaperWeeks * 7 * 86400 / kScanInterval * OfficeFloor::kCells / median;
  std::printf("office: %.2f simulated days (%lu scans of %lu cells, %d robots, %.2f bytes per cell on the wire) "
              "in %.1f s: median %.2fM cell-obs/s over %zu windows of %.0f s, mean %.2fM; %lu cell-observations "
              "acknowledged of %lu\n",
              o.days, static_cast<unsigned long>(scans), static_cast<unsigned long>(OfficeFloor::kCells), o.streams,
              static_cast<double>(wire) / OfficeFloor::kCells, elapsed, median / 1e6, rates.size(), o.seconds,
              mean / 1e6, static_cast<unsigned long>(observations), static_cast<unsigned long>(expected));
  std::printf("office: the paper's %.0f weeks at the median rate: %.2f h (the paper: under an hour, in batch)\n",
              kPaperWeeks, paper_seconds / 3600);
  return ok && observations == expected;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app("fremen_office_load: the paper's office (~213k cells scanned every 5 s) streamed to a running fremend");
  app.add_option("--address", o.address, "fremend's HOST:PORT")->capture_default_str();
  app.add_option("--map", o.map, "grid map to ingest into (created when missing)")->capture_default_str();
  app.add_option("--token", o.token, "bearer token with write access, when the daemon wants one");
  app.add_option("--streams", o.streams, "robots, each scanning a band of the floor on its own stream")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--window", o.window, "unacknowledged scans per robot (the clients' default)")->capture_default_str()->check(CLI::Range(1, 1024));
  app.add_option("--days", o.days, "simulated days to stream, from a Monday 00:00 UTC")
      ->capture_default_str()
      ->check(CLI::Range(1.0 / 17280, 365.0));
  app.add_option("--seconds", o.seconds, "seconds per printed window")->capture_default_str()->check(CLI::Range(0.1, 3600.0));
  app.add_flag("!--no-ceilings", o.ceilings, "skip the ceilings (instruction counts of the workload alone)");
  CLI11_PARSE(app, argc, argv);

  const OfficeFloor floor;
  std::printf("floor: %u×%u cells (%lu), %lu dynamic (%.1f %%), a scan every %.0f s\n", OfficeFloor::kWidth,
              OfficeFloor::kHeight, static_cast<unsigned long>(OfficeFloor::kCells),
              static_cast<unsigned long>(floor.DynamicCells()), 100.0 * floor.DynamicCells() / OfficeFloor::kCells,
              kScanInterval);
  if (o.ceilings) {
    std::printf("ceiling: making the scans, one core: %.0fM cell-obs/s\n", ScanCeiling(floor) / 1e6);
    PrintMemoryCeiling();
  }
  if (!EnsureMap(o)) return 1;
  return Run(o, floor) ? 0 : 1;
}
