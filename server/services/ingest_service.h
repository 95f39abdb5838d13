// fremen.v1.IngestService over storage::MapStore: each Ingest call is an IngestStream
// (server/services/ingest_stream.h), which streams batches into the map's write path; LastSequence tells a
// writer where to continue.
//
// Ingest is served raw (its messages as bytes, parsed by the stream): gRPC's own parsing failure
// looks like the client's end of the stream, so an unparsable message would end the call with OK.
// Thread-safety: gRPC calls the methods from any thread; the service holds no state of its own.
#pragma once

#include "fremen/v1/ingest.grpc.pb.h"
#include "server/rpc/unary_call.h"

namespace fremen::server {

class IngestServiceImpl final : public v1::IngestService::WithRawCallbackMethod_Ingest<
                                    v1::IngestService::WithCallbackMethod_LastSequence<v1::IngestService::Service>> {
 public:
  explicit IngestServiceImpl(const ServiceDeps& deps) : deps_(deps) {}

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Ingest(grpc::CallbackServerContext* context) override;
  grpc::ServerUnaryReactor* LastSequence(grpc::CallbackServerContext* context, const v1::LastSequenceRequest* request,
                                         v1::LastSequenceResponse* response) override;

 private:
  const ServiceDeps deps_;
};

}  // namespace fremen::server
