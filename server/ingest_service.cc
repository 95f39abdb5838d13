#include "server/ingest_service.h"

#include "server/ingest_stream.h"

namespace fremen::server {

grpc::ServerBidiReactor<v1::IngestRequest, v1::IngestResponse>* IngestServiceImpl::Ingest(
    grpc::CallbackServerContext* context) {
  return IngestStream::Start(deps_, context);
}

}  // namespace fremen::server
