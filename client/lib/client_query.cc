// Client: the QueryService calls.
#include "absl/strings/str_cat.h"
#include "client/lib/client.h"
#include "client/lib/status.h"

namespace fremen::client {

v1::PredictionOptions ToProto(const ModelOptions& model) {
  v1::PredictionOptions options;
  options.set_persistence(model.persistence);
  if (model.order) options.set_order(*model.order);
  return options;
}

absl::StatusOr<Predictions> Client::Predict(absl::string_view map, const StateSet& states,
                                            const std::vector<double>& times, const PredictOptions& options,
                                            const CallOptions& call) const {
  v1::PredictRequest request;
  request.set_map(std::string(map));
  *request.mutable_states() = states.proto();
  request.mutable_times()->Assign(times.begin(), times.end());
  *request.mutable_options() = ToProto(options.model);
  if (options.confidence) request.set_confidence(*options.confidence);
  request.set_states_only(options.states_only);
  v1::PredictResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->query().Predict(&context, request, &response);
  });
  if (!status.ok()) return status;
  Predictions predictions;
  predictions.state_count = response.state_count();
  predictions.time_count = response.time_count();
  predictions.probabilities.assign(response.probabilities().begin(), response.probabilities().end());
  predictions.states.assign(response.states().begin(), response.states().end());
  predictions.unobserved.assign(response.unobserved().begin(), response.unobserved().end());
  return predictions;
}

namespace {

// What a region request and a series request share, from the query (RegionQuery or
// RegionSeriesQuery): the map, the box, the options, the output. Returns the box's shape as the
// daemon reads it: a 2-D box may leave z at 0 in both corners.
template <typename Query, typename Request>
GridShape SetRegion(absl::string_view map, const Query& query, Request& request) {
  request.set_map(std::string(map));
  request.mutable_lo()->set_x(query.lo.x);
  request.mutable_lo()->set_y(query.lo.y);
  request.mutable_lo()->set_z(query.lo.z);
  request.mutable_hi()->set_x(query.hi.x);
  request.mutable_hi()->set_y(query.hi.y);
  request.mutable_hi()->set_z(query.hi.z);
  *request.mutable_options() = ToProto(query.model);
  request.set_output(query.output);
  request.set_confidence(query.confidence);
  request.set_chunk_cells(query.chunk_cells);
  const auto extent = [](uint32_t l, uint32_t h) { return h > l ? h - l : 0; };
  const Cell& lo = query.lo;
  const Cell& hi = query.hi;
  return {extent(lo.x, hi.x), extent(lo.y, hi.y), lo.z == 0 && hi.z == 0 ? 1 : extent(lo.z, hi.z)};
}

// Reads a region stream into `assembler`, then its result into `result`. A stream broken half way
// is retried whole (the chunks of one attempt make one answer): `make` gives each attempt a fresh
// assembler.
template <typename Response, typename Result, typename Open, typename MakeAssembler>
absl::Status ReadRegionStream(Connection& connection, const CallOptions& call, absl::string_view map, Open open,
                              MakeAssembler make, absl::StatusOr<Result>& result) {
  return connection.CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    auto assembler = make();
    auto reader = open(context);
    Response chunk;
    absl::Status assembled;
    while (reader->Read(&chunk)) {
      if (assembled = assembler.Add(chunk); !assembled.ok()) {
        context.TryCancel();
        break;
      }
    }
    grpc::Status finished = reader->Finish();
    if (!assembled.ok()) {
      result = assembled;
      return grpc::Status::OK;  // not a transport failure: no retry
    }
    if (finished.ok()) result = assembler.Finish();
    return finished;
  });
}

}  // namespace

absl::StatusOr<RegionArray> Client::PredictRegion(absl::string_view map, const RegionQuery& query,
                                                  const CallOptions& call) const {
  v1::PredictRegionRequest request;
  const GridShape shape = SetRegion(map, query, request);
  request.set_time(query.time);
  absl::StatusOr<RegionArray> result = absl::UnknownError("no attempt");
  absl::Status status = ReadRegionStream<v1::PredictRegionResponse>(
      *connection_, call, map,
      [&](grpc::ClientContext& context) { return connection_->query().PredictRegion(&context, request); },
      [&] { return RegionAssembler(shape, query.output); }, result);
  if (!status.ok()) return status;
  return result;
}

absl::StatusOr<RegionSeries> Client::PredictRegionSeries(absl::string_view map, const RegionSeriesQuery& query,
                                                         const CallOptions& call) const {
  v1::PredictRegionSeriesRequest request;
  const GridShape shape = SetRegion(map, query, request);
  request.mutable_times()->Assign(query.times.begin(), query.times.end());
  absl::StatusOr<RegionSeries> result = absl::UnknownError("no attempt");
  absl::Status status = ReadRegionStream<v1::PredictRegionSeriesResponse>(
      *connection_, call, map,
      [&](grpc::ClientContext& context) { return connection_->query().PredictRegionSeries(&context, request); },
      [&] { return RegionSeriesAssembler(shape, query.output, static_cast<uint32_t>(query.times.size())); },
      result);
  if (!status.ok()) return status;
  return result;
}

absl::StatusOr<std::vector<v1::ScoredState>> Client::TopStates(absl::string_view map, absl::string_view group,
                                                               double time, uint32_t n, const ModelOptions& model,
                                                               const CallOptions& call) const {
  v1::TopStatesRequest request;
  request.set_map(std::string(map));
  request.set_group(std::string(group));
  request.set_time(time);
  request.set_n(n);
  *request.mutable_options() = ToProto(model);
  v1::TopStatesResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->query().TopStates(&context, request, &response);
  });
  if (!status.ok()) return status;
  return std::vector<v1::ScoredState>(response.states().begin(), response.states().end());
}

absl::StatusOr<std::vector<v1::NamedState>> Client::ListAllStates(absl::string_view map, absl::string_view group,
                                                                  const CallOptions& call) const {
  v1::ListStatesRequest request;
  request.set_map(std::string(map));
  request.set_group(std::string(group));
  request.set_page_size(1000);
  std::vector<v1::NamedState> states;
  do {
    v1::ListStatesResponse response;
    absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
      return connection_->query().ListStates(&context, request, &response);
    });
    if (!status.ok()) return status;
    states.insert(states.end(), std::make_move_iterator(response.mutable_states()->begin()),
                  std::make_move_iterator(response.mutable_states()->end()));
    request.set_page_token(response.next_page_token());
  } while (!request.page_token().empty());
  return states;
}

absl::StatusOr<std::vector<Anomaly>> Client::CheckAnomalies(absl::string_view map, const StateSet& states,
                                                            const std::vector<float>& values,
                                                            const std::vector<double>& times, float confidence,
                                                            const ModelOptions& model, const CallOptions& call) const {
  v1::CheckAnomaliesRequest request;
  request.set_map(std::string(map));
  *request.mutable_states() = states.proto();
  request.mutable_values()->Assign(values.begin(), values.end());
  request.mutable_times()->Assign(times.begin(), times.end());
  request.set_confidence(confidence);
  *request.mutable_options() = ToProto(model);
  v1::CheckAnomaliesResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->query().CheckAnomalies(&context, request, &response);
  });
  if (!status.ok()) return status;
  if (response.probabilities_size() != response.anomalous_size()) {
    return absl::DataLossError(absl::StrCat("CheckAnomalies answered ", response.probabilities_size(),
                                            " probabilities but ", response.anomalous_size(), " verdicts"));
  }
  std::vector<Anomaly> anomalies(response.probabilities_size());
  for (int i = 0; i < response.probabilities_size(); ++i) {
    anomalies[i] = {response.probabilities(i), response.anomalous(i)};
  }
  return anomalies;
}

absl::StatusOr<std::optional<v1::StateModel>> Client::GetStateModel(absl::string_view map, const v1::StateRef& state,
                                                                    bool include_spectrum,
                                                                    const CallOptions& call) const {
  v1::GetStateModelRequest request;
  request.set_map(std::string(map));
  *request.mutable_state() = state;
  request.set_include_spectrum(include_spectrum);
  v1::GetStateModelResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->query().GetStateModel(&context, request, &response);
  });
  if (!status.ok()) return status;
  if (!response.has_model()) return std::nullopt;
  return std::move(*response.mutable_model());
}

absl::StatusOr<v1::MapStats> Client::GetMapStats(absl::string_view map, const CallOptions& call) const {
  v1::GetMapStatsRequest request;
  request.set_map(std::string(map));
  v1::GetMapStatsResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->query().GetMapStats(&context, request, &response);
  });
  if (!status.ok()) return status;
  return std::move(*response.mutable_stats());
}

}  // namespace fremen::client
