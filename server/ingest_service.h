// fremen.v1.IngestService over storage::MapStore: each Ingest call is an IngestStream
// (server/ingest_stream.h), which streams batches into the map's write path.
// Thread-safety: gRPC calls Ingest from any thread; the service holds no state of its own.
#pragma once

#include "fremen/v1/ingest.grpc.pb.h"
#include "server/unary_call.h"

namespace fremen::server {

class IngestServiceImpl final : public v1::IngestService::CallbackService {
 public:
  explicit IngestServiceImpl(const ServiceDeps& deps) : deps_(deps) {}

  grpc::ServerBidiReactor<v1::IngestRequest, v1::IngestResponse>* Ingest(
      grpc::CallbackServerContext* context) override;

 private:
  const ServiceDeps deps_;
};

}  // namespace fremen::server
