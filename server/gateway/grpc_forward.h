// The JSON API's calls into the daemon's own gRPC services, over the server's in-process channel
// (grpc::Server::InProcessChannel): an HTTP request becomes a gRPC call with the request's
// "Authorization" header as the call's `authorization` metadata, so that authorization (roles),
// validation and its messages, the access log and the call metrics are exactly those of a gRPC
// client — one path for both, nothing re-implemented on the HTTP side.
//
// A forwarder calls one method with one request and fills one response: Unary(&Stub::Method) for
// the unary methods; IngestOne and WholeRegion for the two streaming ones.
// Thread-safety: a forwarder may run on many threads at once (a stub per call).
#pragma once

#include <grpcpp/grpcpp.h>
#include <httplib.h>

#include <cstdint>
#include <functional>
#include <memory>

#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"

namespace fremen::server {

// The most cells WholeRegion joins into one answer (64 MiB of floats): a bigger box is
// RESOURCE_EXHAUSTED naming its size (gRPC clients stream such boxes chunk by chunk instead).
inline constexpr uint64_t kMaxJoinedRegionCells = uint64_t{16} << 20;

template <typename Request, typename Response>
using Forwarder = std::function<grpc::Status(const std::shared_ptr<grpc::Channel>& channel,
                                             grpc::ClientContext& context, const Request& request, Response& response)>;

// The unary method `method` of `Stub` (e.g. &v1::MapService::Stub::GetMap).
template <typename Stub, typename Request, typename Response>
Forwarder<Request, Response> Unary(grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*)) {
  return [method](const std::shared_ptr<grpc::Channel>& channel, grpc::ClientContext& context, const Request& request,
                  Response& response) {
    Stub stub(channel);
    return (stub.*method)(&context, request, &response);
  };
}

// IngestService.Ingest as one batch: a stream of one request, its one response.
grpc::Status IngestOne(const std::shared_ptr<grpc::Channel>& channel, grpc::ClientContext& context,
                       const v1::IngestRequest& request, v1::IngestResponse& response);

// QueryService.PredictRegion with every chunk joined into one response (offset 0, box_cells, the
// values of the whole box), up to kMaxJoinedRegionCells.
grpc::Status WholeRegion(const std::shared_ptr<grpc::Channel>& channel, grpc::ClientContext& context,
                         const v1::PredictRegionRequest& request, v1::PredictRegionResponse& response);

// A client context for the call `http` asks for: its Authorization header forwarded.
std::unique_ptr<grpc::ClientContext> ForwardedContext(const httplib::Request& http);

}  // namespace fremen::server
