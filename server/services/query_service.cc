#include "server/services/query_service.h"

#include <algorithm>
#include <span>
#include <vector>

#include "absl/strings/str_cat.h"
#include "server/rpc/map_lookup.h"
#include "server/convert/query_args.h"
#include "server/convert/query_convert.h"
#include "server/services/region_series_stream.h"
#include "server/services/region_stream.h"
#include "server/services/state_page.h"
#include "server/convert/state_refs.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/published_model.h"
#include "storage/reconstruction_slots.h"

namespace fremen::server {

namespace {

using storage::MapInfo;
using storage::MapStore;

constexpr MethodSpec kPredict{"Predict", Access::kRead, /*blocking=*/false};
constexpr MethodSpec kPredictLarge{"Predict", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kTopStates{"TopStates", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kCheckAnomalies{"CheckAnomalies", Access::kRead, /*blocking=*/false};
constexpr MethodSpec kCheckAnomaliesLarge{"CheckAnomalies", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kGetStateModel{"GetStateModel", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kReconstruct{"Reconstruct", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kGetMapStats{"GetMapStats", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kListStates{"ListStates", Access::kRead, /*blocking=*/true};

// Up to this many predictions a call is answered inline (tens of microseconds); more go to the pool.
constexpr uint64_t kInlinePredictions = 4096;

constexpr uint32_t kMaxTopStates = 10000;
constexpr uint64_t kMaxReconstructSlots = 1'000'000;
// A Reconstruct answer, one byte per slot per state, stays well inside the default message limit.
constexpr uint64_t kMaxReconstructBytes = uint64_t{8} << 20;

const MethodSpec& SpecFor(uint64_t predictions, const MethodSpec& small, const MethodSpec& large) {
  return predictions <= kInlinePredictions ? small : large;
}

absl::Status DoPredict(const StoreHandle& store, const grpc::ServerContextBase& context,
                       const v1::PredictRequest& request, v1::PredictResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  const MapInfo& info = (*map)->info();
  if (request.times().empty()) return absl::InvalidArgumentError("times is empty; give at least one time");
  if (absl::Status s = CheckTimes(SpanOf(request.times()), "times"); !s.ok()) return s;
  if (request.has_confidence()) {
    if (absl::Status s = CheckConfidence(request.confidence(), 0, 1, "confidence"); !s.ok()) return s;
  } else if (request.states_only()) {
    return absl::InvalidArgumentError("states_only needs confidence: states are p ≥ confidence");
  }
  auto options = PredictOptionsOf(info, request.options(), "options");
  if (!options.ok()) return options.status();
  if (absl::Status s = CheckPredictionCount(RefCount(request.states()), request.times_size()); !s.ok()) return s;
  auto keys = KeysOfRefs(info, request.states(), "states");
  if (!keys.ok()) return keys.status();

  std::vector<uint8_t> observed;
  const std::vector<float> p = (*map)->PredictWithObserved(*keys, SpanOf(request.times()), *options, observed);
  if (!request.states_only()) response.mutable_probabilities()->Add(p.begin(), p.end());
  if (request.has_confidence()) {
    auto& states = *response.mutable_states();
    states.Reserve(static_cast<int>(p.size()));
    for (float v : p) states.AddAlreadyReserved(model::EstimateState(v, request.confidence()));
  }
  response.set_state_count(static_cast<uint32_t>(keys->size()));
  response.set_time_count(static_cast<uint32_t>(request.times_size()));
  for (size_t j = 0; j < observed.size(); ++j) {
    if (!observed[j]) response.add_unobserved(static_cast<uint32_t>(j));
  }
  return absl::OkStatus();
}

absl::Status DoTopStates(const StoreHandle& store, const grpc::ServerContextBase& context,
                         const v1::TopStatesRequest& request, v1::TopStatesResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  const MapInfo& info = (*map)->info();
  if (info.kind != storage::MapKind::kGeneric) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info.name, " is a grid: TopStates ranks the states of a group of a generic map"));
  }
  if (request.group().empty()) return absl::InvalidArgumentError("group is required");
  if (absl::Status s = CheckTime(request.time(), "time"); !s.ok()) return s;
  if (request.n() < 1 || request.n() > kMaxTopStates) {
    return absl::InvalidArgumentError(absl::StrCat("n must be in [1, ", kMaxTopStates, "], got ", request.n()));
  }
  auto options = PredictOptionsOf(info, request.options(), "options");
  if (!options.ok()) return options.status();
  auto top = (*map)->TopN(request.group(), request.time(), request.n(), *options);
  if (!top.ok()) return top.status();
  for (const auto& [key, p] : *top) {
    v1::ScoredState& state = *response.add_states();
    state.set_id(key);
    if (auto label = (*map)->Label(key)) state.set_name(label->first);
    state.set_probability(p);
  }
  return absl::OkStatus();
}

absl::Status DoCheckAnomalies(const StoreHandle& store, const grpc::ServerContextBase& context,
                              const v1::CheckAnomaliesRequest& request, v1::CheckAnomaliesResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  const MapInfo& info = (*map)->info();
  if (absl::Status s = CheckPredictionCount(RefCount(request.states()), 1); !s.ok()) return s;
  auto keys = KeysOfRefs(info, request.states(), "states");
  if (!keys.ok()) return keys.status();
  const int n = static_cast<int>(keys->size());
  if (request.values_size() != n) {
    return absl::InvalidArgumentError(absl::StrCat("values has ", request.values_size(), " elements but states names ",
                                                   n, "; give one value per state"));
  }
  for (int i = 0; i < n; ++i) {
    if (!(request.values(i) >= 0.0f && request.values(i) <= 1.0f)) {
      return absl::InvalidArgumentError(absl::StrCat("values[", i, "] must be in [0, 1], got ", request.values(i)));
    }
  }
  if (request.times_size() != 1 && request.times_size() != n) {
    return absl::InvalidArgumentError(absl::StrCat("times has ", request.times_size(),
                                                   " elements; give one per state (", n, ") or one for all"));
  }
  if (absl::Status s = CheckTimes(SpanOf(request.times()), "times"); !s.ok()) return s;
  if (absl::Status s = CheckConfidence(request.confidence(), 0.5f, 1, "confidence"); !s.ok()) return s;
  auto options = PredictOptionsOf(info, request.options(), "options");
  if (!options.ok()) return options.status();

  // One prediction per run of observations at the same time (typically a whole scan).
  auto& probabilities = *response.mutable_probabilities();
  probabilities.Reserve(n);
  const std::span<const uint64_t> all_keys(*keys);
  for (int i = 0; i < n;) {
    const double t = request.times(request.times_size() == 1 ? 0 : i);
    int end = request.times_size() == 1 ? n : i + 1;
    while (end < n && request.times(end) == t) ++end;
    const std::vector<float> p =
        (*map)->Predict(all_keys.subspan(i, end - i), std::span<const double>(&t, 1), *options);
    probabilities.Add(p.begin(), p.end());
    i = end;
  }
  auto& anomalous = *response.mutable_anomalous();
  anomalous.Reserve(n);
  for (int i = 0; i < n; ++i) {
    anomalous.AddAlreadyReserved(model::IsAnomalous(request.values(i), probabilities[i], request.confidence()));
  }
  return absl::OkStatus();
}

absl::Status DoGetStateModel(const StoreHandle& store, const grpc::ServerContextBase& context,
                             const v1::GetStateModelRequest& request, v1::GetStateModelResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  auto key = KeyOfRef((*map)->info(), request.state(), "state");
  if (!key.ok()) return key.status();
  const std::optional<storage::StateSnapshot> snapshot = (*map)->Snapshot(*key);
  if (!snapshot) return absl::OkStatus();  // never observed: model unset
  StateModelToProto((*map)->info(), (*map)->settings(), *key, *snapshot, request.include_spectrum(),
                    *response.mutable_model());
  return absl::OkStatus();
}

absl::Status DoReconstruct(const StoreHandle& store, const grpc::ServerContextBase& context,
                           const v1::ReconstructRequest& request, v1::ReconstructResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  const MapInfo& info = (*map)->info();
  if (info.lossless_sampling_period <= 0) {
    return absl::FailedPreconditionError(absl::StrCat("map ", info.name,
                                                      " keeps no lossless history (it was created with "
                                                      "lossless_sampling_seconds = 0); only such maps reconstruct"));
  }
  if (absl::Status s = CheckTime(request.start_time(), "start_time"); !s.ok()) return s;
  if (absl::Status s = CheckTime(request.end_time(), "end_time"); !s.ok()) return s;
  if (!(request.start_time() < request.end_time())) {
    return absl::InvalidArgumentError(absl::StrCat("start_time must be < end_time, got [", request.start_time(), ", ",
                                                   request.end_time(), ")"));
  }
  auto window = storage::SlotsOfInterval(info.lossless_origin, info.lossless_sampling_period, request.start_time(),
                                         request.end_time(), kMaxReconstructSlots);
  if (!window.ok()) return window.status();
  const uint64_t slots = window->count;
  if (RefCount(request.states()) * slots > kMaxReconstructBytes) {
    return absl::ResourceExhaustedError(absl::StrCat(RefCount(request.states()), " states × ", slots, " slots = ",
                                                     RefCount(request.states()) * slots, " bytes, more than the ",
                                                     kMaxReconstructBytes, " one answer may hold; split the request"));
  }
  auto keys = KeysOfRefs(info, request.states(), "states");
  if (!keys.ok()) return keys.status();
  response.set_first_slot_time(window->first_time);
  response.set_slot_seconds(info.lossless_sampling_period);
  std::vector<model::SlotState> scratch;
  for (uint64_t key : *keys) {
    std::string& bytes = *response.add_histories()->mutable_slots();
    bytes.assign(slots, static_cast<char>(model::SlotState::kUnobserved));
    const std::optional<storage::StateSnapshot> snapshot = (*map)->Snapshot(key);
    if (!snapshot || !snapshot->lossless || window->begin >= window->end) continue;
    scratch.resize(window->end - window->begin);
    snapshot->lossless->ReconstructInto(window->begin, scratch);
    std::transform(scratch.begin(), scratch.end(), bytes.begin() + static_cast<int64_t>(window->offset),
                   [](model::SlotState s) { return static_cast<char>(s); });
  }
  return absl::OkStatus();
}

absl::Status DoGetMapStats(const StoreHandle& store, const grpc::ServerContextBase& context,
                           const v1::GetMapStatsRequest& request, v1::GetMapStatsResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  MapStatsToProto((*map)->Stats(), *response.mutable_stats());
  return absl::OkStatus();
}

absl::Status DoListStates(const StoreHandle& store, const grpc::ServerContextBase& context,
                          const v1::ListStatesRequest& request, v1::ListStatesResponse& response) {
  auto map = LookUpMap(store, context, request.map());
  if (!map.ok()) return map.status();
  const MapInfo& info = (*map)->info();
  if (info.kind != storage::MapKind::kGeneric) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", info.name, " is a grid: its states are cells, not named states (ListStates lists a generic map's)"));
  }
  auto labels = (*map)->Labels(request.group());
  if (!labels.ok()) return labels.status();
  auto page = PageOfStates(*labels, request.page_size(), request.page_token());
  if (!page.ok()) return page.status();
  for (const storage::StateLabel& label : page->states) {
    v1::NamedState& state = *response.add_states();
    state.set_id(label.key);
    state.set_name(label.name);
    state.set_group(label.group);
  }
  response.set_next_page_token(page->next_page_token);
  response.set_total(labels->size());
  return absl::OkStatus();
}

}  // namespace

grpc::ServerUnaryReactor* QueryServiceImpl::Predict(grpc::CallbackServerContext* context,
                                                    const v1::PredictRequest* request, v1::PredictResponse* response) {
  const uint64_t predictions = RefCount(request->states()) * std::max(request->times_size(), 1);
  return ServeUnary(deps_, context, SpecFor(predictions, kPredict, kPredictLarge), [this, context, request, response] {
    return DoPredict(*deps_.store, *context, *request, *response);
  });
}

grpc::ServerWriteReactor<grpc::ByteBuffer>* QueryServiceImpl::PredictRegion(grpc::CallbackServerContext* context,
                                                                           const grpc::ByteBuffer* request) {
  return RegionStream::Start(deps_, context, *request);
}

grpc::ServerWriteReactor<grpc::ByteBuffer>* QueryServiceImpl::PredictRegionSeries(
    grpc::CallbackServerContext* context, const grpc::ByteBuffer* request) {
  return RegionSeriesStream::Start(deps_, context, *request);
}

grpc::ServerUnaryReactor* QueryServiceImpl::TopStates(grpc::CallbackServerContext* context,
                                                      const v1::TopStatesRequest* request,
                                                      v1::TopStatesResponse* response) {
  return ServeUnary(deps_, context, kTopStates, [this, context, request, response] {
    return DoTopStates(*deps_.store, *context, *request, *response);
  });
}

grpc::ServerUnaryReactor* QueryServiceImpl::CheckAnomalies(grpc::CallbackServerContext* context,
                                                           const v1::CheckAnomaliesRequest* request,
                                                           v1::CheckAnomaliesResponse* response) {
  return ServeUnary(deps_, context, SpecFor(RefCount(request->states()), kCheckAnomalies, kCheckAnomaliesLarge),
                    [this, context, request, response] {
                      return DoCheckAnomalies(*deps_.store, *context, *request, *response);
                    });
}

grpc::ServerUnaryReactor* QueryServiceImpl::GetStateModel(grpc::CallbackServerContext* context,
                                                          const v1::GetStateModelRequest* request,
                                                          v1::GetStateModelResponse* response) {
  return ServeUnary(deps_, context, kGetStateModel, [this, context, request, response] {
    return DoGetStateModel(*deps_.store, *context, *request, *response);
  });
}

grpc::ServerUnaryReactor* QueryServiceImpl::Reconstruct(grpc::CallbackServerContext* context,
                                                        const v1::ReconstructRequest* request,
                                                        v1::ReconstructResponse* response) {
  return ServeUnary(deps_, context, kReconstruct, [this, context, request, response] {
    return DoReconstruct(*deps_.store, *context, *request, *response);
  });
}

grpc::ServerUnaryReactor* QueryServiceImpl::GetMapStats(grpc::CallbackServerContext* context,
                                                        const v1::GetMapStatsRequest* request,
                                                        v1::GetMapStatsResponse* response) {
  return ServeUnary(deps_, context, kGetMapStats, [this, context, request, response] {
    return DoGetMapStats(*deps_.store, *context, *request, *response);
  });
}

grpc::ServerUnaryReactor* QueryServiceImpl::ListStates(grpc::CallbackServerContext* context,
                                                       const v1::ListStatesRequest* request,
                                                       v1::ListStatesResponse* response) {
  return ServeUnary(deps_, context, kListStates, [this, context, request, response] {
    return DoListStates(*deps_.store, *context, *request, *response);
  });
}

}  // namespace fremen::server
