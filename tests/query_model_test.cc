// End-to-end tests of QueryService's other reads against the real fremend: TopStates, ListStates,
// CheckAnomalies, GetStateModel, Reconstruct and GetMapStats — answers equal to the store's, and the
// bad-input rows that apply, each with its exact status code and the field named.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "storage/model/published_model.h"
#include "storage/state_names.h"
#include "tests/query_fixture.h"

namespace fremen::testing {
namespace {

using ::testing::ElementsAreArray;
using ::testing::HasSubstr;

// --- TopStates ---

TEST_F(QueryServiceTest, TopStatesOfAGroup) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::TopStatesRequest request;
  request.set_map("doors");
  request.set_group("kitchen");
  request.set_time(kQueryTime);
  request.set_n(3);
  v1::TopStatesResponse response;
  ASSERT_TRUE(query_->TopStates(CallContext().get(), request, &response).ok());
  ASSERT_EQ(response.states_size(), 3);
  for (int i = 0; i < 3; ++i) {
    const auto& [key, p] = expected_.top_kitchen[i];
    EXPECT_EQ(response.states(i).id(), key);
    EXPECT_EQ(response.states(i).probability(), p);
    const std::string name = response.states(i).name();
    EXPECT_EQ(storage::StateIdOfName(name), key) << name;
    EXPECT_LT(std::stoi(name.substr(5)), 5) << name;  // a kitchen door
  }
  EXPECT_GE(response.states(0).probability(), response.states(2).probability());

  request.set_n(100);  // more than the group holds: all of it
  ASSERT_TRUE(query_->TopStates(CallContext().get(), request, &response).ok());
  EXPECT_EQ(response.states_size(), 5);
}

TEST_F(QueryServiceTest, TopStatesBadInput) {
  CreateMap(GridMap("lab", kNx, kNy));
  CreateMap(GenericMap("doors"));
  v1::TopStatesRequest r;
  r.set_map("doors");
  r.set_group("kitchen");
  r.set_time(kT0);
  r.set_n(3);
  v1::TopStatesResponse response;
  const auto call = [&](const v1::TopStatesRequest& request) {
    return query_->TopStates(CallContext().get(), request, &response);
  };
  EXPECT_STATUS(call(r), NOT_FOUND, "kitchen");
  v1::TopStatesRequest bad = r;
  bad.set_n(0);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "n must be in [1, 10000]");
  bad.set_n(10001);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "n must be");
  bad = r;
  bad.clear_group();
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "group");
  bad = r;
  bad.set_time(std::numeric_limits<double>::infinity());
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "time");
  bad = r;
  bad.set_map("lab");
  EXPECT_STATUS(call(bad), FAILED_PRECONDITION, "is a grid");
}

// --- ListStates ---

TEST_F(QueryServiceTest, ListStatesWalksTheNamedStatesByName) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  std::vector<std::string> names;
  for (int i = 0; i < kDoors; ++i) names.push_back(DoorName(i));
  std::sort(names.begin(), names.end());
  v1::ListStatesRequest request;
  request.set_map("doors");
  request.set_page_size(3);
  std::vector<v1::NamedState> listed;
  int pages = 0;
  do {
    v1::ListStatesResponse response;
    ASSERT_TRUE(query_->ListStates(CallContext().get(), request, &response).ok());
    EXPECT_EQ(response.total(), static_cast<uint64_t>(kDoors));
    listed.insert(listed.end(), response.states().begin(), response.states().end());
    request.set_page_token(response.next_page_token());
    ++pages;
  } while (!request.page_token().empty() && pages < 100);
  EXPECT_EQ(pages, (kDoors + 2) / 3);
  ASSERT_EQ(listed.size(), names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(listed[i].name(), names[i]);
    EXPECT_EQ(listed[i].id(), storage::StateIdOfName(names[i]));
    const int door = std::stoi(names[i].substr(5));
    EXPECT_EQ(listed[i].group(), door < 5 ? "kitchen" : "hall") << names[i];
  }

  v1::ListStatesRequest hall;
  hall.set_map("doors");
  hall.set_group("hall");
  v1::ListStatesResponse response;
  ASSERT_TRUE(query_->ListStates(CallContext().get(), hall, &response).ok());
  EXPECT_EQ(response.states_size(), kDoors - 5);
  EXPECT_EQ(response.total(), static_cast<uint64_t>(kDoors - 5));
  EXPECT_TRUE(response.next_page_token().empty());
  for (const v1::NamedState& state : response.states()) EXPECT_EQ(state.group(), "hall") << state.name();
}

TEST_F(QueryServiceTest, ListStatesBadInput) {
  CreateMap(GridMap("lab", kNx, kNy));
  CreateMap(GenericMap("doors"));
  v1::ListStatesResponse response;
  const auto call = [&](const v1::ListStatesRequest& request) {
    return query_->ListStates(CallContext().get(), request, &response);
  };
  v1::ListStatesRequest r;
  r.set_map("doors");
  ASSERT_TRUE(call(r).ok());  // a map no batch has named states in: an empty list
  EXPECT_EQ(response.states_size(), 0);
  EXPECT_EQ(response.total(), 0u);
  v1::ListStatesRequest bad = r;
  bad.set_group("kitchen");
  EXPECT_STATUS(call(bad), NOT_FOUND, "kitchen");
  bad = r;
  bad.set_page_size(-1);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "page_size");
  bad = r;
  bad.set_page_token("no such token");
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "page_token");
  bad = r;
  bad.set_map("lab");
  EXPECT_STATUS(call(bad), FAILED_PRECONDITION, "is a grid");
  bad.set_map("nowhere");
  EXPECT_STATUS(call(bad), NOT_FOUND, "nowhere");
}

// --- CheckAnomalies ---

TEST_F(QueryServiceTest, AnomaliesFollowTheModel) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  // Every probe cell observed both occupied and free at the query time.
  v1::CheckAnomaliesRequest request;
  request.set_map("lab");
  request.set_confidence(0.8f);
  std::vector<float> values;
  for (auto [x, y] : expected_.probe_cells) {
    for (float s : {0.0f, 1.0f}) {
      request.mutable_states()->mutable_cells()->add_x(x);
      request.mutable_states()->mutable_cells()->add_y(y);
      request.add_values(s);
      values.push_back(s);
    }
  }
  request.add_times(expected_.times[1]);
  v1::CheckAnomaliesResponse response;
  ASSERT_TRUE(query_->CheckAnomalies(CallContext().get(), request, &response).ok());
  ASSERT_EQ(response.anomalous_size(), static_cast<int>(values.size()));
  int anomalies = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    const float p = expected_.predict[1 * expected_.probe_cells.size() + i / 2];
    EXPECT_EQ(response.probabilities(i), p) << i;
    EXPECT_EQ(response.anomalous(i), model::IsAnomalous(values[i], p, 0.8)) << i;
    anomalies += response.anomalous(i);
  }
  EXPECT_GT(anomalies, 0);  // a static free cell seen occupied, at least

  // One time per observation, in runs of equal times.
  request.clear_times();
  const auto time_of = [](size_t i) { return (i / 4) % 2; };
  for (size_t i = 0; i < values.size(); ++i) request.add_times(expected_.times[time_of(i)]);
  ASSERT_TRUE(query_->CheckAnomalies(CallContext().get(), request, &response).ok());
  for (size_t i = 0; i < values.size(); ++i) {
    const float p = expected_.predict[time_of(i) * expected_.probe_cells.size() + i / 2];
    EXPECT_EQ(response.probabilities(i), p) << i;
    EXPECT_EQ(response.anomalous(i), model::IsAnomalous(values[i], p, 0.8)) << i;
  }
}

TEST_F(QueryServiceTest, AnomaliesBadInput) {
  CreateMap(GridMap("lab", kNx, kNy));
  v1::CheckAnomaliesRequest r;
  r.set_map("lab");
  r.mutable_states()->mutable_cells()->add_x(1);
  r.mutable_states()->mutable_cells()->add_y(1);
  r.add_values(1);
  r.add_times(kT0);
  r.set_confidence(0.9f);
  v1::CheckAnomaliesResponse response;
  const auto call = [&](const v1::CheckAnomaliesRequest& request) {
    return query_->CheckAnomalies(CallContext().get(), request, &response);
  };
  EXPECT_TRUE(call(r).ok());
  v1::CheckAnomaliesRequest bad = r;
  bad.add_values(0);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "values has 2 elements");
  bad = r;
  bad.set_values(0, 1.5f);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "values[0]");
  bad = r;
  bad.set_values(0, std::numeric_limits<float>::quiet_NaN());
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "values[0]");
  bad = r;
  bad.add_times(kT0);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "times has 2 elements");
  bad = r;
  bad.clear_times();
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "times has 0 elements");
  bad = r;
  bad.set_times(0, std::numeric_limits<double>::quiet_NaN());
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "times[0]");
  bad = r;
  bad.set_confidence(0.3f);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "confidence must be in [0.5, 1]");
  bad = r;
  bad.mutable_states()->mutable_cells()->set_y(0, kNy);
  EXPECT_STATUS(call(bad), OUT_OF_RANGE, "states.cells[0]");
}

// --- GetStateModel ---

TEST_F(QueryServiceTest, StateModelOfADynamicCell) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::GetStateModelRequest request;
  request.set_map("lab");
  *request.mutable_state()->mutable_cell() = Cell(4, 7);
  request.set_include_spectrum(true);
  v1::GetStateModelResponse response;
  ASSERT_TRUE(query_->GetStateModel(CallContext().get(), request, &response).ok());
  const v1::StateModel& m = response.model();
  const model::CompactStateModel& want = *expected_.dynamic_cell.model;
  EXPECT_FALSE(m.never_changed());
  EXPECT_EQ(m.cell().x(), 4u);
  EXPECT_EQ(m.cell().y(), 7u);
  EXPECT_EQ(m.observations(), static_cast<uint64_t>(kHours));
  EXPECT_EQ(m.first_time(), kT0);
  EXPECT_EQ(m.last_time(), kT0 + (kHours - 1) * 3600.0);
  EXPECT_DOUBLE_EQ(m.mean(), want.spectrum().gamma0());
  ASSERT_EQ(m.spectrum_size(), 24);
  for (int k = 0; k < 24; ++k) {
    EXPECT_NEAR(m.spectrum(k).period_seconds(), 604800.0 / (k + 1), 1e-6);
    EXPECT_DOUBLE_EQ(m.spectrum(k).amplitude(), 2 * std::abs(want.spectrum().gamma(k)));
  }
  // A daily rhythm: P's strongest component is the day.
  EXPECT_EQ(m.selected_order(), static_cast<uint32_t>(want.published().order()));
  EXPECT_GE(m.selected_order(), 1u);
  ASSERT_EQ(m.published_size(), static_cast<int>(want.published().components().size()));
  EXPECT_NEAR(m.published(0).period_seconds(), 86400, 1e-6);
  EXPECT_FLOAT_EQ(m.published_mean(), want.published().alpha0());
  ASSERT_EQ(m.order_errors_size(), 6);
  for (int l = 0; l <= 5; ++l) EXPECT_DOUBLE_EQ(m.order_errors(l).error(), want.order_errors().ErrorRate(l));
  EXPECT_GT(m.order_errors(0).error(), m.order_errors(m.selected_order()).error());
  EXPECT_EQ(m.persistence().last_time(), kT0 + (kHours - 1) * 3600.0);
  EXPECT_GT(m.persistence().tau_seconds(), 0);
  EXPECT_FALSE(m.has_lossless());

  request.set_include_spectrum(false);
  ASSERT_TRUE(query_->GetStateModel(CallContext().get(), request, &response).ok());
  EXPECT_EQ(response.model().spectrum_size(), 0);
}

TEST_F(QueryServiceTest, StateModelOfStaticAndUnobservedStates) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::GetStateModelRequest request;
  request.set_map("lab");
  *request.mutable_state()->mutable_cell() = Cell(2, 3);  // always free
  v1::GetStateModelResponse response;
  ASSERT_TRUE(query_->GetStateModel(CallContext().get(), request, &response).ok());
  EXPECT_TRUE(response.model().never_changed());
  EXPECT_EQ(response.model().observations(), static_cast<uint64_t>(kHours));
  EXPECT_EQ(response.model().mean(), 0);
  EXPECT_EQ(response.model().published_size(), 0);

  // A point in cell (50, 20), never observed: no model.
  request.mutable_state()->mutable_point()->set_x(-1.0 + 5.05);
  request.mutable_state()->mutable_point()->set_y(2.05);
  response.Clear();
  ASSERT_TRUE(query_->GetStateModel(CallContext().get(), request, &response).ok());
  EXPECT_FALSE(response.has_model());

  request.set_map("doors");
  request.mutable_state()->set_name(DoorName(7));
  ASSERT_TRUE(query_->GetStateModel(CallContext().get(), request, &response).ok());
  EXPECT_EQ(response.model().name(), DoorName(7));
  EXPECT_EQ(response.model().group(), "hall");
  EXPECT_EQ(response.model().id(), storage::StateIdOfName(DoorName(7)));
}

TEST_F(QueryServiceTest, StateModelOfALosslessState) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::GetStateModelRequest request;
  request.set_map("history");
  request.mutable_state()->set_id(3);
  v1::GetStateModelResponse response;
  ASSERT_TRUE(query_->GetStateModel(CallContext().get(), request, &response).ok());
  const v1::LosslessModel& l = response.model().lossless();
  const model::LosslessHistory& want = *expected_.lossless_state.lossless;
  EXPECT_EQ(l.origin(), kT0);
  EXPECT_EQ(l.sampling_seconds(), 600);
  EXPECT_EQ(l.slot_count(), kLosslessSlots);
  ASSERT_EQ(l.unobserved_size(), 1);  // id 3's gap
  EXPECT_EQ(l.unobserved(0).start(), kT0 + 600.0 * 160);
  EXPECT_EQ(l.unobserved(0).end(), kT0 + 600.0 * 200);
  EXPECT_EQ(l.outliers_size(), static_cast<int>(want.outliers().Intervals().size()));
  EXPECT_DOUBLE_EQ(l.estimation_error(), want.EstimationError().rate());
  EXPECT_DOUBLE_EQ(l.prediction_error(), want.PredictionError().rate());
  EXPECT_EQ(l.selected_order(), static_cast<uint32_t>(want.model().order()));
  EXPECT_EQ(l.published_size(), static_cast<int>(want.model().components().size()));
  EXPECT_FALSE(l.truncated());
}

TEST_F(QueryServiceTest, StateModelBadInput) {
  CreateMap(GridMap("lab", kNx, kNy));
  v1::GetStateModelRequest r;
  r.set_map("lab");
  v1::GetStateModelResponse response;
  EXPECT_STATUS(query_->GetStateModel(CallContext().get(), r, &response), INVALID_ARGUMENT, "state is required");
  *r.mutable_state()->mutable_cell() = Cell(kNx, 0);
  EXPECT_STATUS(query_->GetStateModel(CallContext().get(), r, &response), OUT_OF_RANGE, "state.cell");
  r.mutable_state()->set_id(4);
  EXPECT_STATUS(query_->GetStateModel(CallContext().get(), r, &response), FAILED_PRECONDITION, "state.id");
}

// --- Reconstruct ---

TEST_F(QueryServiceTest, ReconstructGivesTheExactPast) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::ReconstructRequest request;
  request.set_map("history");
  for (uint64_t id = 1; id <= 4; ++id) request.mutable_states()->add_ids(id);  // 4: never observed
  // From two slots before the origin to the end of the history.
  request.set_start_time(kT0 - 1200);
  request.set_end_time(kT0 + 600.0 * kLosslessSlots);
  v1::ReconstructResponse response;
  const grpc::Status status = query_->Reconstruct(CallContext().get(), request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.first_slot_time(), kT0 - 1200);
  EXPECT_EQ(response.slot_seconds(), 600);
  ASSERT_EQ(response.histories_size(), 4);
  for (int i = 0; i < 3; ++i) {
    const std::string& slots = response.histories(i).slots();
    ASSERT_EQ(slots.size(), kLosslessSlots + 2);
    EXPECT_EQ(slots[0], 2);
    EXPECT_EQ(slots[1], 2);
    for (uint64_t s = 0; s < kLosslessSlots; ++s) {
      ASSERT_EQ(slots[s + 2], static_cast<char>(expected_.lossless_slots[i][s])) << "id " << i + 1 << " slot " << s;
    }
  }
  EXPECT_EQ(response.histories(2).slots()[2 + 170], 2);  // id 3's gap
  EXPECT_EQ(response.histories(3).slots(), std::string(kLosslessSlots + 2, 2));
}

TEST_F(QueryServiceTest, ReconstructBadInput) {
  CreateMap(GenericMap("doors"));
  CreateMap(GenericMap("history", 600));
  v1::ReconstructRequest r;
  r.set_map("history");
  r.mutable_states()->add_ids(1);
  r.set_start_time(kT0);
  r.set_end_time(kT0 + 3600);
  v1::ReconstructResponse response;
  const auto call = [&](const v1::ReconstructRequest& request) {
    return query_->Reconstruct(CallContext().get(), request, &response);
  };
  EXPECT_TRUE(call(r).ok());
  v1::ReconstructRequest bad = r;
  bad.set_map("doors");
  EXPECT_STATUS(call(bad), FAILED_PRECONDITION, "lossless");
  bad = r;
  bad.set_end_time(kT0);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "start_time must be < end_time");
  bad = r;
  bad.set_end_time(kT0 + 600.0 * 1e6 + 600);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "slots");
  bad = r;
  bad.set_start_time(std::numeric_limits<double>::quiet_NaN());
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "start_time");
  bad = r;
  bad.set_end_time(1e14);
  EXPECT_STATUS(call(bad), INVALID_ARGUMENT, "end_time");
  bad = r;
  for (int i = 0; i < 20; ++i) bad.mutable_states()->add_ids(i);
  bad.set_end_time(kT0 + 600.0 * 500000);  // 21 × 500000 bytes
  EXPECT_STATUS(call(bad), RESOURCE_EXHAUSTED, "21 states × 500000 slots");
}

// --- GetMapStats ---

TEST_F(QueryServiceTest, MapStatsEqualTheStore) {
  CreateAndFillMaps();
  ASSERT_FALSE(HasFatalFailure());
  v1::GetMapStatsRequest request;
  request.set_map("lab");
  v1::GetMapStatsResponse response;
  ASSERT_TRUE(query_->GetMapStats(CallContext().get(), request, &response).ok());
  const v1::MapStats& s = response.stats();
  const storage::MapStats& want = expected_.lab_stats;
  EXPECT_EQ(s.states(), uint64_t{kObservedNx} * kNy);
  EXPECT_EQ(s.states(), want.totals.states);
  EXPECT_EQ(s.dynamic_states(), want.totals.dynamic_states);
  // Half the observed cells have a rhythm; the rest never changed.
  EXPECT_EQ(s.dynamic_states(), uint64_t{kObservedNx} * kNy / 2);
  EXPECT_EQ(s.observations(), uint64_t{kObservedNx} * kNy * kHours);
  EXPECT_THAT(s.order_histogram(), ElementsAreArray(want.totals.order_histogram));
  // Summed over states in whatever order the shards hold them after recovery.
  EXPECT_NEAR(s.mean_prediction_error(), want.mean_prediction_error, 1e-12);
  EXPECT_GT(s.disk_bytes(), 0u);
  EXPECT_GT(s.memory_bytes(), 0u);
  EXPECT_GT(s.compression_ratio(), 0);
  EXPECT_EQ(s.lossless_estimation_error(), 0);

  request.set_map("history");
  ASSERT_TRUE(query_->GetMapStats(CallContext().get(), request, &response).ok());
  EXPECT_DOUBLE_EQ(response.stats().lossless_estimation_error(), expected_.lossless_stats.estimation_error);
  EXPECT_DOUBLE_EQ(response.stats().lossless_prediction_error(), expected_.lossless_stats.lossless_prediction_error);

  request.set_map("nowhere");
  EXPECT_STATUS(query_->GetMapStats(CallContext().get(), request, &response), NOT_FOUND, "nowhere");
}

}  // namespace
}  // namespace fremen::testing
