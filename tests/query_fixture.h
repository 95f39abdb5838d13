// The fixture of QueryService's end-to-end tests (query_service_test.cc, query_model_test.cc): a
// fresh fremend per test, and maps filled without the IngestService — a map is created through the
// API, the daemon is stopped, the test writes scans and publishes models with storage::Store on the
// daemon's data directory (noting what the store computes), and restarts the daemon, which must then
// answer exactly what the store computed.
// Thread-compatible: one test thread.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "storage/map_store.h"
#include "storage/store.h"
#include "tests/fremend_fixture.h"

namespace fremen::testing {

using Metadata = std::vector<std::pair<std::string, std::string>>;

inline constexpr double kT0 = 1.7e9;
inline constexpr int kHours = 21 * 24;  // three weeks of hourly scans
inline constexpr uint32_t kNx = 64, kNy = 48, kObservedNx = 32;
inline constexpr double kQueryTime = kT0 + kHours * 3600.0 + 5 * 3600.0;
inline constexpr int kDoors = 10;
inline constexpr uint64_t kLosslessSlots = 3 * 144;  // three days of 10-minute slots

// A cell's observed value at scan hour h (cells with x ≥ kObservedNx are never observed): x % 4 = 0
// a daily rhythm with a little noise, 1 a weekday rhythm, 2 always free, 3 always occupied on odd y.
float CellValue(uint32_t x, uint32_t y, int h);
v1::Map GridMap(const std::string& name, uint32_t nx, uint32_t ny, bool persistence = true);
// Lossless history when lossless_sampling > 0, from kT0.
v1::Map GenericMap(const std::string& name, double lossless_sampling = 0);
v1::CellIndex Cell(uint32_t x, uint32_t y, uint32_t z = 0);
std::string DoorName(int i);

// What the store computed for the data it was given, to compare the daemon's answers with.
struct Expected {
  std::vector<std::pair<uint32_t, uint32_t>> probe_cells;  // (x, y)
  std::vector<uint64_t> probe_keys;
  std::vector<double> times;
  std::vector<float> predict;              // probe cells × times
  std::vector<float> predict_persistence;  // with persistence
  std::vector<float> predict_order0;       // order 0
  std::vector<float> region;               // the whole grid at kQueryTime
  storage::StateSnapshot dynamic_cell, static_cell;
  std::vector<std::pair<uint64_t, float>> top_kitchen;
  std::vector<float> door_p;  // doors 0..9 at kQueryTime
  std::vector<std::vector<model::SlotState>> lossless_slots;  // ids 1..3, slots [0, kLosslessSlots)
  storage::StateSnapshot lossless_state;
  storage::MapStats lab_stats, lossless_stats;
};

class QueryServiceTest : public DaemonTest {
 protected:
  void SetUp() override {
    DaemonTest::SetUp();
    if (!HasFatalFailure()) Connect();
  }

  void Connect() {
    maps_ = v1::MapService::NewStub(daemon_->NewChannel());
    query_ = v1::QueryService::NewStub(daemon_->NewChannel());
  }

  void CreateMap(const v1::Map& map, const Metadata& metadata = {}) {
    v1::CreateMapRequest request;
    *request.mutable_map() = map;
    v1::CreateMapResponse response;
    const grpc::Status status = maps_->CreateMap(CallContext(metadata).get(), request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }

  // Stops the daemon, hands its data directory's store to `f`, and restarts the daemon.
  void WithStore(const std::function<void(storage::Store&)>& f, const std::vector<std::string>& args = {}) {
    StopDaemon();
    {
      auto store = storage::Store::Open(data_dir(), storage::StoreOptions());
      ASSERT_TRUE(store.ok()) << store.status();
      f(**store);
      ASSERT_TRUE((*store)->Close().ok());
    }
    StartDaemon(args);
    Connect();
  }

  // The maps every data test uses: "lab" (a grid with three weeks of scans), "doors" (generic,
  // named, grouped), "history" (generic, lossless), all published; the store's answers in expected_.
  void CreateAndFillMaps(const std::vector<std::string>& args = {}, const Metadata& metadata = {}) {
    CreateMap(GridMap("lab", kNx, kNy), metadata);
    CreateMap(GenericMap("doors"), metadata);
    CreateMap(GenericMap("history", 600), metadata);
    if (HasFatalFailure()) return;
    WithStore([this](storage::Store& store) { Fill(store); }, args);
  }

  // Writes the data of the three maps and notes the store's answers.
  void Fill(storage::Store& store);

  grpc::Status Predict(const v1::PredictRequest& request, v1::PredictResponse* response,
                       const Metadata& metadata = {}) {
    return query_->Predict(CallContext(metadata).get(), request, response);
  }

  // A Predict request for the probe cells at the expected times.
  v1::PredictRequest ProbeRequest() const {
    v1::PredictRequest request;
    request.set_map("lab");
    for (auto [x, y] : expected_.probe_cells) {
      request.mutable_states()->mutable_cells()->add_x(x);
      request.mutable_states()->mutable_cells()->add_y(y);
    }
    for (double t : expected_.times) request.add_times(t);
    return request;
  }

  struct RegionResult {
    grpc::Status status;
    std::vector<v1::PredictRegionResponse> chunks;
  };
  RegionResult Region(const v1::PredictRegionRequest& request,
                      std::chrono::milliseconds deadline = std::chrono::milliseconds(30000),
                      const Metadata& metadata = {}) {
    auto context = CallContext(metadata);
    context->set_deadline(std::chrono::system_clock::now() + deadline);
    RegionResult result;
    auto reader = query_->PredictRegion(context.get(), request);
    v1::PredictRegionResponse chunk;
    while (reader->Read(&chunk)) result.chunks.push_back(chunk);
    result.status = reader->Finish();
    return result;
  }

  v1::PredictRegionRequest WholeLab(v1::RegionOutput output) const {
    v1::PredictRegionRequest request;
    request.set_map("lab");
    *request.mutable_lo() = Cell(0, 0);
    *request.mutable_hi() = Cell(kNx, kNy);
    request.set_time(kQueryTime);
    request.set_output(output);
    return request;
  }

  // The floats or bytes of a stream's chunks, in order, checking that each chunk starts where the
  // previous ended and says the box's size.
  template <typename T>
  std::vector<T> Assemble(const RegionResult& result, uint64_t box_cells) {
    std::vector<T> values;
    for (const auto& chunk : result.chunks) {
      EXPECT_EQ(chunk.offset(), values.size());
      EXPECT_EQ(chunk.box_cells(), box_cells);
      if constexpr (std::is_same_v<T, float>) {
        values.insert(values.end(), chunk.float_values().begin(), chunk.float_values().end());
      } else {
        values.insert(values.end(), chunk.bytes_values().begin(), chunk.bytes_values().end());
      }
    }
    EXPECT_EQ(values.size(), box_cells);
    return values;
  }

  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::QueryService::Stub> query_;
  Expected expected_;
};

// The status code and message of a failed call, for one-line expectations.
#define EXPECT_STATUS(status, code, text)                                     \
  do {                                                                        \
    const grpc::Status s_ = (status);                                         \
    EXPECT_EQ(s_.error_code(), grpc::StatusCode::code) << s_.error_message(); \
    EXPECT_THAT(s_.error_message(), ::testing::HasSubstr(text));              \
  } while (0)

}  // namespace fremen::testing
