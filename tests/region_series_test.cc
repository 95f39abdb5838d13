// End-to-end tests of QueryService.PredictRegionSeries against the real fremend: every frame equals
// PredictRegion at its time, value for value, for every output and option set; the cells whose
// prediction cannot change with time cross the wire once; bad requests are refused naming the
// field, and the daemon keeps serving.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "tests/query_fixture.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

class RegionSeriesTest : public QueryServiceTest {
 protected:
  struct SeriesResult {
    grpc::Status status;
    std::vector<v1::PredictRegionSeriesResponse> chunks;
  };

  SeriesResult Series(const v1::PredictRegionSeriesRequest& request) {
    auto context = CallContext({});
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    SeriesResult result;
    auto reader = query_->PredictRegionSeries(context.get(), request);
    v1::PredictRegionSeriesResponse chunk;
    while (reader->Read(&chunk)) result.chunks.push_back(chunk);
    result.status = reader->Finish();
    return result;
  }

  static v1::PredictRegionSeriesRequest WholeLabSeries(v1::RegionOutput output, const std::vector<double>& times) {
    v1::PredictRegionSeriesRequest request;
    request.set_map("lab");
    *request.mutable_lo() = Cell(0, 0);
    *request.mutable_hi() = Cell(kNx, kNy);
    request.mutable_times()->Assign(times.begin(), times.end());
    request.set_output(output);
    return request;
  }

  // A chunk's values as bytes (a float's bits for float outputs), so that frames compare exactly.
  static std::vector<std::string> Values(const v1::PredictRegionSeriesResponse& chunk) {
    std::vector<std::string> out;
    for (const float f : chunk.float_values()) out.emplace_back(reinterpret_cast<const char*>(&f), sizeof f);
    for (const char b : chunk.bytes_values()) out.emplace_back(1, b);
    return out;
  }
  static std::vector<std::string> Values(const v1::PredictRegionResponse& chunk) {
    std::vector<std::string> out;
    for (const float f : chunk.float_values()) out.emplace_back(reinterpret_cast<const char*>(&f), sizeof f);
    for (const char b : chunk.bytes_values()) out.emplace_back(1, b);
    return out;
  }

  // Each frame t equals PredictRegion of the whole lab at times[t] with `single`'s other fields,
  // value for value.
  void ExpectEachFrameIsPredictRegion(const std::vector<std::vector<std::string>>& frames,
                                      const std::vector<double>& times, v1::PredictRegionRequest single) {
    const uint64_t cells = uint64_t{kNx} * kNy;
    single.set_map("lab");
    *single.mutable_lo() = Cell(0, 0);
    *single.mutable_hi() = Cell(kNx, kNy);
    for (size_t t = 0; t < times.size(); ++t) {
      single.set_time(times[t]);
      const RegionResult region = Region(single);
      ASSERT_TRUE(region.status.ok()) << region.status.error_message();
      std::vector<std::string> expected;
      for (const auto& chunk : region.chunks) {
        for (std::string& v : Values(chunk)) expected.push_back(std::move(v));
      }
      ASSERT_EQ(frames[t].size(), expected.size());
      for (uint64_t i = 0; i < cells; ++i) ASSERT_EQ(frames[t][i], expected[i]) << "time " << t << " cell " << i;
    }
  }

  // The frames of a series stream, checking its layout (query.proto): the base in order, then the
  // times in order, each chunk where the previous ended. `varying` gets the varying cells' indices
  // and `wire_values` the values the stream carried.
  std::vector<std::vector<std::string>> Frames(const SeriesResult& result, uint64_t cells, uint32_t times,
                                               std::vector<uint64_t>& varying, uint64_t& wire_values) {
    std::vector<std::string> base(cells);
    std::vector<std::vector<std::string>> frames;
    uint64_t base_cells = 0, frame_values = 0;
    wire_values = 0;
    varying.clear();
    for (const auto& chunk : result.chunks) {
      EXPECT_EQ(chunk.box_cells(), cells);
      EXPECT_EQ(chunk.time_count(), times);
      const std::vector<std::string> values = Values(chunk);
      wire_values += values.size();
      if (chunk.base()) {
        EXPECT_TRUE(frames.empty()) << "a base chunk after a frame";
        EXPECT_EQ(chunk.offset(), base_cells);
        EXPECT_EQ(chunk.varying_mask().size(), (chunk.cells() + 7) / 8);
        size_t k = 0;
        for (uint64_t j = 0; j < chunk.cells(); ++j) {
          if ((static_cast<uint8_t>(chunk.varying_mask()[j / 8]) >> (j % 8)) & 1) {
            varying.push_back(chunk.offset() + j);
          } else if (k < values.size()) {
            base[chunk.offset() + j] = values[k++];
          }
        }
        EXPECT_EQ(k, values.size()) << "values for the constant cells only";
        base_cells += chunk.cells();
        continue;
      }
      EXPECT_EQ(base_cells, cells) << "a frame before the whole base";
      EXPECT_EQ(chunk.varying_cells(), varying.size());
      if (frame_values == 0) {
        EXPECT_EQ(chunk.time_index(), frames.size());
        frames.push_back(base);
      }
      EXPECT_EQ(chunk.offset(), frame_values);
      for (const std::string& v : values) {
        if (frame_values < varying.size()) frames.back()[varying[frame_values++]] = v;
      }
      if (frame_values == varying.size()) frame_values = 0;
    }
    EXPECT_EQ(base_cells, cells);
    if (varying.empty()) frames.assign(times, base);
    EXPECT_EQ(frames.size(), times);
    return frames;
  }
};

// Every output, with and without persistence and at order 0: frame i is PredictRegion at times[i],
// value for value; the constant cells — never observed (x ≥ 32), never changed (x % 4 = 2, 3) —
// are sent once, the others once per time.
TEST_F(RegionSeriesTest, EveryFrameIsPredictRegionAtItsTime) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  const std::vector<double> times = {kQueryTime, kT0 + 3600 * 30.5, kQueryTime + 86400 * 3 + 1234, kQueryTime,
                                     kT0};
  const uint64_t cells = uint64_t{kNx} * kNy;
  struct Case {
    v1::RegionOutput output;
    bool persistence;
    int order;
  };
  const Case cases[] = {{v1::REGION_OUTPUT_FLOAT, false, -1},   {v1::REGION_OUTPUT_UINT8, false, -1},
                        {v1::REGION_OUTPUT_ENTROPY, false, -1}, {v1::REGION_OUTPUT_STATES, false, -1},
                        {v1::REGION_OUTPUT_FLOAT, true, -1},    {v1::REGION_OUTPUT_UINT8, false, 0}};
  uint64_t default_varying = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(::testing::Message() << "output " << c.output << " persistence " << c.persistence << " order "
                                    << c.order);
    v1::PredictRegionSeriesRequest request = WholeLabSeries(c.output, times);
    request.set_confidence(0.6f);
    request.mutable_options()->set_persistence(c.persistence);
    if (c.order >= 0) request.mutable_options()->set_order(c.order);
    request.set_chunk_cells(300);  // several base chunks and several chunks a frame
    const SeriesResult series = Series(request);
    ASSERT_TRUE(series.status.ok()) << series.status.error_message();
    std::vector<uint64_t> varying;
    uint64_t wire_values = 0;
    const auto frames = Frames(series, cells, times.size(), varying, wire_values);
    ASSERT_FALSE(HasFailure());
    // Sent once: the constant cells; once per time: the varying ones.
    EXPECT_EQ(wire_values, cells - varying.size() + varying.size() * times.size());
    for (const uint64_t i : varying) {
      const uint32_t x = i % kNx;
      ASSERT_LT(x, kObservedNx) << "never observed, yet varying: cell " << i;
      ASSERT_TRUE(x % 4 == 0 || x % 4 == 1) << "never changed, yet varying: cell " << i;
    }
    if (c.order == 0 && !c.persistence) {
      EXPECT_TRUE(varying.empty());
    }
    if (c.order < 0 && !c.persistence) {
      EXPECT_GT(varying.size(), 0u);
      default_varying = varying.size();
    }
    if (c.persistence) {
      EXPECT_GE(varying.size(), default_varying);
    }

    v1::PredictRegionRequest single;
    single.set_output(c.output);
    single.set_confidence(0.6f);
    *single.mutable_options() = request.options();
    ExpectEachFrameIsPredictRegion(frames, times, single);
    ASSERT_FALSE(HasFatalFailure());
  }
}

// More times than one block of times holds (kMaxSeriesTimesPerBlock, 16, for a box this small):
// three blocks, the last one short, and every frame still PredictRegion at its time, in order.
TEST_F(RegionSeriesTest, ManyTimesGoInBlocksOfSeveralEachFrameAtItsTime) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  std::vector<double> times;
  for (int i = 0; i < 37; ++i) times.push_back(kQueryTime + 1877.0 * i);
  const uint64_t cells = uint64_t{kNx} * kNy;
  const SeriesResult series = Series(WholeLabSeries(v1::REGION_OUTPUT_FLOAT, times));
  ASSERT_TRUE(series.status.ok()) << series.status.error_message();
  std::vector<uint64_t> varying;
  uint64_t wire_values = 0;
  const auto frames = Frames(series, cells, times.size(), varying, wire_values);
  ASSERT_FALSE(HasFailure());
  EXPECT_GT(varying.size(), 0u);
  v1::PredictRegionRequest single;
  single.set_output(v1::REGION_OUTPUT_FLOAT);
  ExpectEachFrameIsPredictRegion(frames, times, single);
}

// A sub-box of a 3-D grid, chunks of the server's choice.
TEST_F(RegionSeriesTest, ASubBoxInServerChunks) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  const std::vector<double> times = {kQueryTime, kQueryTime + 6 * 3600};
  v1::PredictRegionSeriesRequest request = WholeLabSeries(v1::REGION_OUTPUT_FLOAT, times);
  *request.mutable_lo() = Cell(3, 5);
  *request.mutable_hi() = Cell(37, 9);
  const SeriesResult series = Series(request);
  ASSERT_TRUE(series.status.ok()) << series.status.error_message();
  EXPECT_EQ(series.chunks.size(), 1u + times.size());  // the base, then one chunk a time
  std::vector<uint64_t> varying;
  uint64_t wire_values = 0;
  const auto frames = Frames(series, 34 * 4, times.size(), varying, wire_values);
  ASSERT_FALSE(HasFailure());
  for (size_t t = 0; t < times.size(); ++t) {
    v1::PredictRegionRequest single = WholeLab(v1::REGION_OUTPUT_FLOAT);
    *single.mutable_lo() = request.lo();
    *single.mutable_hi() = request.hi();
    single.set_time(times[t]);
    const std::vector<float> expected = Assemble<float>(Region(single), 34 * 4);
    for (size_t i = 0; i < expected.size(); ++i) {
      float got;
      std::memcpy(&got, frames[t][i].data(), sizeof got);
      ASSERT_EQ(got, expected[i]) << "time " << t << " cell " << i;
    }
  }
}

TEST_F(RegionSeriesTest, BadRequestsNameTheFieldAndTheDaemonServesOn) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  const v1::PredictRegionSeriesRequest good = WholeLabSeries(v1::REGION_OUTPUT_UINT8, {kQueryTime, kT0});
  v1::PredictRegionSeriesRequest r = good;
  r.clear_times();
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "times");
  r = good;
  r.add_times(std::numeric_limits<double>::quiet_NaN());
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "times[2]");
  r = good;
  r.set_times(1, -5);
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "times[1]");
  r = good;
  r.set_times(0, 2e13);
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "times[0]");
  r = good;
  for (int i = 0; i < 1000; ++i) r.add_times(kT0 + i);
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "times must hold 1 to 1000");
  r = good;
  *r.mutable_hi() = Cell(kNx + 1, kNy);
  EXPECT_STATUS(Series(r).status, OUT_OF_RANGE, "hi.x");
  r = good;
  *r.mutable_lo() = Cell(0, 7);
  *r.mutable_hi() = Cell(kNx, 7);
  EXPECT_STATUS(Series(r).status, OUT_OF_RANGE, "lo.y");
  r = good;
  r.set_output(static_cast<v1::RegionOutput>(99));
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "output");
  r = good;
  r.set_output(v1::REGION_OUTPUT_STATES);
  r.set_confidence(1.5f);
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "confidence");
  r = good;
  r.mutable_options()->set_order(9);
  EXPECT_STATUS(Series(r).status, INVALID_ARGUMENT, "options.order");
  r = good;
  r.set_map("doors");
  EXPECT_STATUS(Series(r).status, FAILED_PRECONDITION, "not a grid");
  r = good;
  r.set_map("nowhere");
  EXPECT_STATUS(Series(r).status, NOT_FOUND, "nowhere");
  CreateMap(GridMap("wide", 4096, 2048));
  r = good;
  r.set_map("wide");
  *r.mutable_hi() = Cell(4096, 1025);
  EXPECT_STATUS(Series(r).status, OUT_OF_RANGE, "at most 4194304 cells");
  *r.mutable_hi() = Cell(4096, 1024);  // 2^22 cells, never observed: one base, no frames
  const SeriesResult unobserved = Series(r);
  ASSERT_TRUE(unobserved.status.ok()) << unobserved.status.error_message();
  for (const auto& chunk : unobserved.chunks) EXPECT_TRUE(chunk.base());
  EXPECT_EQ(unobserved.chunks.back().varying_cells(), 0u);

  const SeriesResult ok = Series(good);
  EXPECT_TRUE(ok.status.ok()) << ok.status.error_message();
}

}  // namespace
}  // namespace fremen::testing
