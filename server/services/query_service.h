// fremen.v1.QueryService over storage::MapStore: predictions (many states × many times, regions,
// top-n of a group), anomaly checks, a state's full model, exact reconstruction of lossless
// histories and map statistics (docs/model.md, "Queries"). Every method is a read (read or write
// token).
//
// Small predictions run inline on the gRPC thread (a single-state Predict is a few microseconds of
// work; the hop to a pool would cost more); large ones, and the methods whose cost grows with the
// map or a state's history (TopStates, GetStateModel, Reconstruct, GetMapStats, ListStates), run on the
// blocking pool so that they cannot hold up the gRPC threads. PredictRegion and
// PredictRegionSeries stream (server/services/region_stream.h, region_series_stream.h).
// Thread-safety: gRPC calls the handlers from any thread; the service holds no state of its own.
#pragma once

#include "fremen/v1/query.grpc.pb.h"
#include "server/rpc/unary_call.h"

namespace fremen::server {

// The region methods are raw: their streams parse the request and write serialized chunks
// (server/services/block_stream.h).
class QueryServiceImpl final
    : public v1::QueryService::WithRawCallbackMethod_PredictRegion<
          v1::QueryService::WithRawCallbackMethod_PredictRegionSeries<v1::QueryService::CallbackService>> {
 public:
  explicit QueryServiceImpl(const ServiceDeps& deps) : deps_(deps) {}

  grpc::ServerUnaryReactor* Predict(grpc::CallbackServerContext* context, const v1::PredictRequest* request,
                                    v1::PredictResponse* response) override;
  grpc::ServerWriteReactor<grpc::ByteBuffer>* PredictRegion(grpc::CallbackServerContext* context,
                                                             const grpc::ByteBuffer* request) override;
  grpc::ServerWriteReactor<grpc::ByteBuffer>* PredictRegionSeries(grpc::CallbackServerContext* context,
                                                                   const grpc::ByteBuffer* request) override;
  grpc::ServerUnaryReactor* TopStates(grpc::CallbackServerContext* context, const v1::TopStatesRequest* request,
                                      v1::TopStatesResponse* response) override;
  grpc::ServerUnaryReactor* CheckAnomalies(grpc::CallbackServerContext* context,
                                           const v1::CheckAnomaliesRequest* request,
                                           v1::CheckAnomaliesResponse* response) override;
  grpc::ServerUnaryReactor* GetStateModel(grpc::CallbackServerContext* context,
                                          const v1::GetStateModelRequest* request,
                                          v1::GetStateModelResponse* response) override;
  grpc::ServerUnaryReactor* Reconstruct(grpc::CallbackServerContext* context, const v1::ReconstructRequest* request,
                                        v1::ReconstructResponse* response) override;
  grpc::ServerUnaryReactor* GetMapStats(grpc::CallbackServerContext* context, const v1::GetMapStatsRequest* request,
                                        v1::GetMapStatsResponse* response) override;
  grpc::ServerUnaryReactor* ListStates(grpc::CallbackServerContext* context, const v1::ListStatesRequest* request,
                                       v1::ListStatesResponse* response) override;

 private:
  const ServiceDeps deps_;
};

}  // namespace fremen::server
